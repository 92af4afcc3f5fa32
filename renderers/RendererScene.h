#pragma once
// What a registered renderer draws, built by its factory (RendererRegistry.h) from a scene
// description. The core holds it without knowing its type; the renderer's own folder reads it
// back (the scivis renderer: renderers/scivis/Registration.h).
namespace renderers {

class RendererScene {
 public:
  virtual ~RendererScene() = default;
};

}  // namespace renderers
