#pragma once
// One rank's brick rendered over the whole canvas, as IceT's icetCompositeImage wants its input:
// full-frame buffers of which only `viewport` is valid. The brick is cut and loaded exactly as
// the DFB's data-parallel driver does it (renderers/scivis/bricks/BrickPlan.h, BrickLoad.h), and
// only the tiles the brick projects to are rendered (BrickFrameDriver::bricksOfTile decides, as
// for the DFB), so both compositors receive the same fragments from the same rendering work.
//
// Buffers are in canvas rows (row 0 = the top row). IceT calls its row 0 the bottom one; since
// no projection matrix is handed to IceT, it never looks at where rows are, and tiles and
// viewports given in canvas rows come back in canvas rows.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "dfb/PixelOp.h"
#include "dfb/TileOperation.h"
#include "renderers/Renderer.h"
#include "renderers/SceneDesc.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "renderers/scivis/bricks/Bricks.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace icetbench {

class BrickImage {
 public:
  // opaque: also fill rgba8 (tone-mapped here, which commutes with depth compositing) and depth.
  BrickImage(std::shared_ptr<const renderers::SceneDesc> desc,
             const renderers::RenderSettings& settings, int brick, int bricks, bool opaque,
             dfb::ToneMapSettings toneMap);

  // Renders `frame` seen by `camera` (accumulation id 0: every frame its own epoch, as an orbit
  // makes it). `planner` is this rank's DFB driver of the same scene and bricks; only its plan
  // (which tiles need which brick) is used.
  void render(const dfb::FrameInfo& frame, const renderers::CameraDesc& camera,
              const renderers::scivis::BrickFrameDriver& planner);

  const std::vector<float>& color() const { return color_; }  // premultiplied linear RGBA
  const std::vector<std::uint32_t>& rgba8() const { return rgba8_; }
  const std::vector<float>& depth() const { return depth_; }  // 0 near .. 1 nothing
  // x, y, width, height of the pixels rendered this frame (all zero when none).
  const std::array<int, 4>& viewport() const { return viewport_; }

 private:
  std::shared_ptr<const renderers::SceneDesc> desc_;
  renderers::RenderSettings settings_;
  renderers::scivis::BrickPlan plan_;
  bool opaque_;
  dfb::ToneMapSettings toneMap_;
  float depthScale_;  // depth = t / (t + depthScale_): monotonic, in [0, 1)
  std::unique_ptr<renderers::scivis::SciVisScene> scene_;
  std::unique_ptr<renderers::scivis::SciVisRenderer> renderer_;
  std::vector<float> color_, depth_;
  std::vector<std::uint32_t> rgba8_;
  std::array<int, 4> viewport_{0, 0, 0, 0};
};

// Brick ids front to back as seen from `eye`: the bricks come from a k-d split, so a plane
// between two groups of them always exists, and the group on the eye's side goes first (the
// order IceT's icetCompositeOrder needs; the DFB sorts fragments per pixel instead).
std::vector<int> visibilityOrder(const std::vector<renderers::scivis::BrickPlan>& bricks,
                                 renderers::Vec3 eye);

}  // namespace icetbench
