#pragma once
// Ready-made pictures as a renderer, so `dfbwall show` puts them on a wall exactly as a job's
// frames go: tiles through the DFB, pieces routed to the displays the window touches. Each frame
// draws the picture it shows (PictureSequence.h) fitted into the canvas (PictureFit.h) as RGBA8
// display pixels straight away: no float pixels, no tone mapping, nothing accumulated.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "renderers/RenderScene.h"
#include "renderers/Renderer.h"
#include "renderers/RendererScene.h"
#include "renderers/SceneExtension.h"
#include "renderers/picture/PictureFile.h"
#include "renderers/picture/PictureFit.h"

namespace renderers::picture {

inline const std::string kPictureName = "picture";

// What `dfbwall show` asks for, carried in SceneDesc::extensions under kPictureName.
struct PictureDesc final : SceneExtension {
  std::vector<std::string> files;  // expanded (PictureSequence.h), in play order
  Filter filter = Filter::Bilinear;
  std::uint32_t background = 0xff000000u;  // RGBA8 around the picture and under its alpha
  bool loop = false;                       // after the last picture, the first again

  std::unique_ptr<SceneExtension> clone() const override {
    return std::make_unique<PictureDesc>(*this);
  }
  bool empty() const override { return files.empty(); }
  std::vector<std::string> inputFiles() const override { return files; }
  std::uint64_t bytes() const override { return 0; }
};

// A scene of nothing but `desc`, for buildRenderScene(kPictureName, ...).
SceneDesc pictureScene(const PictureDesc& desc);

// What the renderer draws from: the files checked (every header read, so a missing, foreign or
// oversized file fails the setup, not a later frame) and the first picture decoded.
class PictureSet final : public RendererScene {
 public:
  explicit PictureSet(const PictureDesc& desc);
  const PictureDesc& desc() const { return desc_; }
  // Picture `index`, flattened over the background; decodes all but the first on each call.
  std::shared_ptr<const Picture> picture(std::size_t index) const;

 private:
  PictureDesc desc_;
  std::shared_ptr<const Picture> first_;
};

class PictureRenderer final : public Renderer {
 public:
  PictureRenderer(const PictureSet& pictures, const RenderSettings& settings);
  void beginFrame(const dfb::FrameInfo& frame, const CameraDesc& camera) override;
  void render(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
              std::uint32_t samples, dfb::Tile& out) const override;

 private:
  const PictureSet& pictures_;
  int width_, height_;
  std::size_t shown_ = 0;
  std::unique_ptr<FittedPicture> fitted_;  // the picture shown, fitted into the canvas
};

// Registers the renderer kPictureName (RendererRegistry.h); calling it again does nothing.
void registerPictures();

}  // namespace renderers::picture
