#include "renderers/picture/PictureRenderer.h"

#include <mutex>
#include <utility>

#include "base/Error.h"
#include "renderers/RendererRegistry.h"
#include "renderers/picture/PictureSequence.h"

namespace renderers::picture {
namespace {

std::shared_ptr<const Picture> decode(const PictureDesc& desc, std::size_t index) {
  Picture picture = readPicture(desc.files.at(index));
  flattenOver(picture, desc.background);
  return std::make_shared<const Picture>(std::move(picture));
}

}  // namespace

SceneDesc pictureScene(const PictureDesc& desc) {
  SceneDesc scene;
  scene.extensions.set(kPictureName, desc.clone());
  return scene;
}

PictureSet::PictureSet(const PictureDesc& desc) : desc_(desc) {
  if (desc_.files.empty()) throw base::Error("show: no picture to show");
  for (const std::string& file : desc_.files) readPictureHeader(file);
  first_ = decode(desc_, 0);
}

std::shared_ptr<const Picture> PictureSet::picture(std::size_t index) const {
  return index == 0 ? first_ : decode(desc_, index);
}

PictureRenderer::PictureRenderer(const PictureSet& pictures, const RenderSettings& settings)
    : pictures_(pictures), width_(settings.width), height_(settings.height) {
  const PictureDesc& desc = pictures_.desc();
  fitted_ = std::make_unique<FittedPicture>(pictures_.picture(0), width_, height_, desc.filter,
                                            desc.background);
}

void PictureRenderer::beginFrame(const dfb::FrameInfo& frame, const CameraDesc& /*camera*/) {
  const PictureDesc& desc = pictures_.desc();
  const std::size_t index = pictureOfFrame(frame.frameId, desc.files.size(), desc.loop);
  if (index == shown_) return;
  fitted_ = std::make_unique<FittedPicture>(pictures_.picture(index), width_, height_, desc.filter,
                                            desc.background);
  shown_ = index;
}

void PictureRenderer::render(const dfb::Region& region, std::uint32_t accumulationId,
                             std::uint32_t firstSample, std::uint32_t samples,
                             dfb::Tile& out) const {
  prepareTile(region, accumulationId, firstSample, samples, out);
  out.color.clear();  // display pixels only (RenderSettings::displayPixels)
  out.rgba8.resize(static_cast<std::size_t>(region.pixelCount()));
  const std::size_t width = static_cast<std::size_t>(region.x1 - region.x0);
  for (int y = region.y0; y < region.y1; ++y)
    fitted_->row(y, region.x0, region.x1,
                 out.rgba8.data() + static_cast<std::size_t>(y - region.y0) * width);
}

void registerPictures() {
  static std::once_flag once;
  std::call_once(once, [] {
    RendererFactory factory;
    factory.build = [](RenderScene& scene) {
      const auto* desc =
          dynamic_cast<const PictureDesc*>(scene.desc->extensions.find(kPictureName));
      if (!desc) throw base::Error("renderer picture: the scene names no pictures (dfbwall show)");
      scene.registered = std::make_shared<const PictureSet>(*desc);
    };
    factory.make = [](const RenderScene& scene,
                      const RenderSettings& settings) -> std::unique_ptr<Renderer> {
      const auto* set = dynamic_cast<const PictureSet*>(scene.registered.get());
      if (!set) throw base::Error("renderer picture: the scene was not built for it");
      return std::make_unique<PictureRenderer>(*set, settings);
    };
    registerRenderer(kPictureName, std::move(factory));
  });
}

}  // namespace renderers::picture
