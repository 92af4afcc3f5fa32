#pragma once
// The drawing both presenters share: upload a frame to a texture, draw it 1:1 with a GLSL 330
// full-screen triangle that texelFetches (no filtering, no scaling, so every pixel survives
// exactly), read pixels back. Every GL function comes from the loader the caller passes, never
// from a linked libGL (see wall/CMakeLists.txt for why).
#include <cstdint>
#include <memory>
#include <string>

#include "wall/image/Image.h"

namespace wall {

using GlProc = void (*)();
using GlProcLoader = GlProc (*)(const char* name);

class GlFrameDrawer {
 public:
  // Needs a current OpenGL 3.3 core context; resolves the GL functions with `loader` and builds
  // the shader. Throws base::Error naming a missing function or the shader log.
  explicit GlFrameDrawer(GlProcLoader loader);
  // Frees the GL objects: the same context must be current.
  ~GlFrameDrawer();
  GlFrameDrawer(const GlFrameDrawer&) = delete;
  GlFrameDrawer& operator=(const GlFrameDrawer&) = delete;

  // Makes the texture `width` x `height` (reallocated only when the size changes; its contents
  // are then undefined until uploaded).
  void resize(int width, int height);
  // Copies `w` x `h` pixels into the texture at (x, y): `first` points at the first of them,
  // rows `stride` pixels apart. Row 0 is the frame's top.
  void upload(const std::uint32_t* first, int stride, int x, int y, int w, int h);
  // Draws the texture with its top-left at the drawable's top-left; the rest of the drawable is
  // cleared to black. Waits for nothing; call finish() or swap to be sure it is drawn.
  void draw(int drawableWidth, int drawableHeight);
  // glFinish.
  void finish();
  // The top-left `width` x `height` pixels of the drawable, rows top first. `frontBuffer` reads
  // GL_FRONT (a double-buffered window after its swap); otherwise the default read buffer.
  Image read(int width, int height, int drawableHeight, bool frontBuffer);

  std::string version() const;   // GL_VERSION
  std::string renderer() const;  // GL_RENDERER

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wall
