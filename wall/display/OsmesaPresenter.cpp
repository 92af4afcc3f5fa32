#include "wall/display/OsmesaPresenter.h"

#include <GL/osmesa.h>

#include <optional>
#include <string>
#include <vector>

#include "base/Error.h"
#include "wall/display/GlFrameDrawer.h"

namespace wall {
namespace {

// OSMesa's own entry points: with an OSMesa context current, GL calls resolved through GLVND's
// libGL do nothing (docs/design.md, "Stack pitfalls"), so every GL function comes from here.
GlProc osmesaProc(const char* name) { return OSMesaGetProcAddress(name); }

class OsmesaPresenter : public Presenter {
 public:
  OsmesaPresenter(int width, int height) {
    if (width <= 0 || height <= 0)
      throw base::Error("OSMesa presenter: size " + std::to_string(width) + "x" +
                        std::to_string(height) + " must be positive");
    const int attributes[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_DEPTH_BITS,
                              0,
                              OSMESA_STENCIL_BITS,
                              0,
                              OSMESA_ACCUM_BITS,
                              0,
                              OSMESA_PROFILE,
                              OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION,
                              3,
                              OSMESA_CONTEXT_MINOR_VERSION,
                              3,
                              0};
    context_ = OSMesaCreateContextAttribs(attributes, nullptr);
    if (!context_) throw base::Error("OSMesa cannot create an OpenGL 3.3 core profile context");
    try {
      resize(width, height);
      drawer_.emplace(&osmesaProc);
    } catch (...) {
      OSMesaDestroyContext(context_);
      throw;
    }
  }

  ~OsmesaPresenter() override {
    makeCurrent();
    drawer_.reset();
    OSMesaDestroyContext(context_);
  }

  void beginFrame(int width, int height) override {
    if (width != width_ || height != height_)
      resize(width, height);
    else
      makeCurrent();
    drawer_->resize(width, height);
  }

  void uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) override {
    makeCurrent();
    drawer_->upload(first, stride, rect.x0, rect.y0, rect.width(), rect.height());
  }

  // The drawable is the buffer itself (no front buffer): drawn and finished here, so swap() has
  // nothing left to do.
  void draw() override {
    makeCurrent();
    drawer_->draw(width_, height_);
    drawer_->finish();
  }

  void swap() override {}

  Image readBack() override {
    makeCurrent();
    return drawer_->read(width_, height_, height_, false);
  }

  std::string describe() const override {
    return "OSMesa offscreen, OpenGL " + drawer_->version() + ", " + drawer_->renderer();
  }

 private:
  void makeCurrent() {
    // Uploads come piece by piece: skip the switch when this context is current already (only
    // this presenter ever binds its buffer, so the buffer is ours then too).
    if (OSMesaGetCurrentContext() == context_) return;
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_))
      throw base::Error("OSMesaMakeCurrent failed");
  }

  void resize(int width, int height) {
    width_ = width;
    height_ = height;
    buffer_.assign(static_cast<size_t>(width) * height, 0);
    // A new buffer: bind it even when the context is current.
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_))
      throw base::Error("OSMesaMakeCurrent failed");
  }

  OSMesaContext context_ = nullptr;
  std::vector<std::uint32_t> buffer_;  // the drawable OSMesa renders into
  int width_ = 0, height_ = 0;
  std::optional<GlFrameDrawer> drawer_;
};

}  // namespace

std::unique_ptr<Presenter> makeOsmesaPresenter(int width, int height) {
  return std::make_unique<OsmesaPresenter>(width, height);
}

}  // namespace wall
