#include "wall/display/GlfwPresenter.h"

#define GLFW_INCLUDE_NONE  // no GL header: GL goes through GlFrameDrawer's table
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include <bit>
#include <cmath>
#include <optional>
#include <utility>

#include "base/Error.h"
#include "wall/display/GlFrameDrawer.h"

// From GLFW/glfw3native.h, which cannot be included here: with GLFW_EXPOSE_NATIVE_X11 it wants
// X11/extensions/Xrandr.h, and libxrandr-dev is no dependency of ours. libglfw exports both.
extern "C" {
::Display* glfwGetX11Display(void);
Window glfwGetX11Window(GLFWwindow* window);
}

namespace wall {
namespace {

std::string glfwProblem() {
  const char* description = nullptr;
  const int code = glfwGetError(&description);
  return code == GLFW_NO_ERROR ? "unknown GLFW error"
                               : std::string(description ? description : "no description");
}

GlProc glfwProc(const char* name) { return glfwGetProcAddress(name); }

// One channel of an X pixel scaled to 8 bits, whatever the visual's mask.
std::uint32_t channel(unsigned long pixel, unsigned long mask) {
  if (!mask) return 0;
  const int shift = std::countr_zero(mask);
  const int bits = std::popcount(mask);
  const unsigned long v = (pixel & mask) >> shift;
  return static_cast<std::uint32_t>(bits == 8 ? v : v * 255 / ((1ul << bits) - 1));
}

// The top-left `width` x `height` pixels of `window` as the X server holds them: what the screen
// shows, opaque. GL cannot tell us this: after a swap the back buffer is undefined, and Mesa's
// software GLX (Xvfb, llvmpipe) reads GL_FRONT of a double-buffered window as zeros.
Image readWindow(GLFWwindow* glfwWindow, const std::string& title, int width, int height) {
  ::Display* display = glfwGetX11Display();
  const Window window = glfwGetX11Window(glfwWindow);
  XWindowAttributes a;
  if (!display || !window || !XGetWindowAttributes(display, window, &a) ||
      a.map_state != IsViewable)
    throw base::Error("display '" + title +
                      "': the window is not visible, so it cannot be read back");
  int rootX = 0, rootY = 0;
  Window child;
  XTranslateCoordinates(display, window, a.root, 0, 0, &rootX, &rootY, &child);
  XWindowAttributes root;
  XGetWindowAttributes(display, a.root, &root);
  // XGetImage of a window not wholly on screen is an X error, which ends the process.
  if (width > a.width || height > a.height || rootX < 0 || rootY < 0 ||
      rootX + width > root.width || rootY + height > root.height)
    throw base::Error("display '" + title +
                      "': the window is not wholly on screen; cannot read it back");
  XImage* x = XGetImage(display, window, 0, 0, static_cast<unsigned>(width),
                        static_cast<unsigned>(height), AllPlanes, ZPixmap);
  if (!x) throw base::Error("display '" + title + "': XGetImage failed");
  Image out(width, height);
  for (int y = 0; y < height; ++y) {
    for (int col = 0; col < width; ++col) {
      const unsigned long p = XGetPixel(x, col, y);
      out.at(col, y) = channel(p, x->red_mask) | channel(p, x->green_mask) << 8 |
                       channel(p, x->blue_mask) << 16 | 0xff000000u;
    }
  }
  XDestroyImage(x);
  return out;
}

class GlfwPresenter : public Presenter {
 public:
  explicit GlfwPresenter(const WindowOptions& o) : title_(o.title) {
    GLFWmonitor* monitor = nullptr;
    if (o.fullscreen) {
      int count = 0;
      GLFWmonitor** monitors = glfwGetMonitors(&count);
      if (o.monitor < 0 || o.monitor >= count)
        throw base::Error("display '" + o.title + "': monitor " + std::to_string(o.monitor) +
                          " requested, but " + std::to_string(count) + " monitor(s) are connected");
      monitor = monitors[o.monitor];
    }
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    glfwWindowHint(GLFW_AUTO_ICONIFY, GLFW_FALSE);  // a wall keeps showing when focus moves
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);       // placed first, then shown
    window_ = glfwCreateWindow(o.width, o.height, o.title.c_str(), monitor, nullptr);
    if (!window_)
      throw base::Error("display '" + o.title +
                        "': cannot open a window with an OpenGL 3.3 core "
                        "context: " +
                        glfwProblem());
    if (!monitor && o.x >= 0 && o.y >= 0) glfwSetWindowPos(window_, o.x, o.y);
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, &GlfwPresenter::onKey);
    glfwSetMouseButtonCallback(window_, &GlfwPresenter::onButton);
    glfwSetCursorPosCallback(window_, &GlfwPresenter::onCursor);
    glfwSetScrollCallback(window_, &GlfwPresenter::onScroll);
    glfwShowWindow(window_);
    try {
      glfwMakeContextCurrent(window_);
      glfwSwapInterval(o.vsync ? 1 : 0);
      drawer_.emplace(&glfwProc);
    } catch (...) {
      glfwDestroyWindow(window_);
      throw;
    }
  }

  ~GlfwPresenter() override {
    glfwMakeContextCurrent(window_);
    drawer_.reset();
    glfwMakeContextCurrent(nullptr);
    glfwDestroyWindow(window_);
  }

  void beginFrame(int width, int height) override {
    makeCurrent();
    drawer_->resize(width, height);
    lastWidth_ = width;
    lastHeight_ = height;
  }

  void uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) override {
    makeCurrent();
    drawer_->upload(first, stride, rect.x0, rect.y0, rect.width(), rect.height());
  }

  // Into the back buffer, finished: the swap after the wall's barrier then only exchanges
  // buffers, so the displays change together.
  void draw() override {
    makeCurrent();
    int fbWidth = 0, fbHeight = 0;
    glfwGetFramebufferSize(window_, &fbWidth, &fbHeight);
    drawer_->draw(fbWidth, fbHeight);
    drawer_->finish();
  }

  void swap() override {
    makeCurrent();
    glfwSwapBuffers(window_);
    glfwPollEvents();
  }

  Image readBack() override {
    makeCurrent();
    drawer_->finish();
    return readWindow(window_, title_, lastWidth_, lastHeight_);
  }

  bool closeRequested() const override { return glfwWindowShouldClose(window_); }

  std::vector<WallInput> takeInput() override { return std::exchange(input_, {}); }
  void pollEvents() override { glfwPollEvents(); }

  std::string describe() const override {
    return "GLFW window '" + title_ + "', OpenGL " + drawer_->version() + ", " +
           drawer_->renderer();
  }

 private:
  // Uploads come piece by piece: switch contexts only when another window's is current.
  void makeCurrent() {
    if (glfwGetCurrentContext() != window_) glfwMakeContextCurrent(window_);
  }

  // Called by glfwPollEvents on this (the main) thread. Keys by their meaning on a US layout
  // and the keypad; '+' is shift-'=' there, so '=' counts as plus too.
  static void onKey(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/) {
    if (action == GLFW_RELEASE) return;
    auto* self = static_cast<GlfwPresenter*>(glfwGetWindowUserPointer(window));
    std::optional<WallKey> k;
    switch (key) {
      case GLFW_KEY_LEFT:
        k = WallKey::Left;
        break;
      case GLFW_KEY_RIGHT:
        k = WallKey::Right;
        break;
      case GLFW_KEY_UP:
        k = WallKey::Up;
        break;
      case GLFW_KEY_DOWN:
        k = WallKey::Down;
        break;
      case GLFW_KEY_EQUAL:
      case GLFW_KEY_KP_ADD:
        k = WallKey::Plus;
        break;
      case GLFW_KEY_MINUS:
      case GLFW_KEY_KP_SUBTRACT:
        k = WallKey::Minus;
        break;
      case GLFW_KEY_ESCAPE:
        if (action == GLFW_PRESS) k = WallKey::Escape;
        break;
      default:
        break;
    }
    if (!k) return;
    WallInput in;
    in.key = *k;
    self->cursorAt(in);
    self->queue(in);
  }

  // A drag: from where its button went down (the left orbits; the right, or Shift, pans),
  // moves coalesced into one event until something else is queued.
  static void onButton(GLFWwindow* window, int button, int action, int mods) {
    auto* self = static_cast<GlfwPresenter*>(glfwGetWindowUserPointer(window));
    if (button != GLFW_MOUSE_BUTTON_LEFT && button != GLFW_MOUSE_BUTTON_RIGHT) return;
    if (action == GLFW_RELEASE) {
      self->dragging_ = false;
      return;
    }
    WallInput at;
    self->cursorAt(at);
    self->dragging_ = true;
    self->dragPan_ = button == GLFW_MOUSE_BUTTON_RIGHT || (mods & GLFW_MOD_SHIFT) != 0;
    self->dragFrom_[0] = at.x;
    self->dragFrom_[1] = at.y;
    self->lastCursor_[0] = at.x;
    self->lastCursor_[1] = at.y;
  }

  static void onCursor(GLFWwindow* window, double x, double y) {
    auto* self = static_cast<GlfwPresenter*>(glfwGetWindowUserPointer(window));
    const int cx = static_cast<int>(std::floor(x)), cy = static_cast<int>(std::floor(y));
    const int dx = cx - self->lastCursor_[0], dy = cy - self->lastCursor_[1];
    self->lastCursor_[0] = cx;
    self->lastCursor_[1] = cy;
    self->cursorKnown_ = true;
    if (!self->dragging_ || (dx == 0 && dy == 0)) return;
    std::vector<WallInput>& q = self->input_;
    if (!q.empty() && q.back().kind == WallInput::Kind::Drag && q.back().x == self->dragFrom_[0] &&
        q.back().y == self->dragFrom_[1] && q.back().pan == self->dragPan_) {
      q.back().dx += dx;
      q.back().dy += dy;
      return;
    }
    WallInput in;
    in.kind = WallInput::Kind::Drag;
    in.x = self->dragFrom_[0];
    in.y = self->dragFrom_[1];
    in.dx = dx;
    in.dy = dy;
    in.pan = self->dragPan_;
    self->queue(in);
  }

  static void onScroll(GLFWwindow* window, double /*dx*/, double dy) {
    auto* self = static_cast<GlfwPresenter*>(glfwGetWindowUserPointer(window));
    const int notches = static_cast<int>(std::lround(dy));
    if (notches == 0) return;
    WallInput in;
    in.kind = WallInput::Kind::Scroll;
    in.dy = notches;
    self->cursorAt(in);
    self->queue(in);
  }

  // Where the cursor was when the event at hand happened: as the events before it left it (the
  // pointer may have moved on since: asking the X server now would tell where it is now).
  void cursorAt(WallInput& in) const {
    if (cursorKnown_) {
      in.x = lastCursor_[0];
      in.y = lastCursor_[1];
      return;
    }
    double x = 0, y = 0;
    glfwGetCursorPos(window_, &x, &y);
    in.x = static_cast<int>(std::floor(x));
    in.y = static_cast<int>(std::floor(y));
  }
  void queue(const WallInput& in) {
    if (input_.size() < 256) input_.push_back(in);  // bounded if nobody takes
  }

  std::string title_;
  GLFWwindow* window_ = nullptr;
  std::vector<WallInput> input_;
  bool dragging_ = false, dragPan_ = false, cursorKnown_ = false;
  int dragFrom_[2] = {0, 0}, lastCursor_[2] = {0, 0};
  std::optional<GlFrameDrawer> drawer_;
  int lastWidth_ = 0, lastHeight_ = 0;
};

}  // namespace

GlfwSession::GlfwSession() {
  if (!glfwInit())
    throw base::Error(
        "GLFW cannot start (is there an X display? offscreen walls use --offscreen): " +
        glfwProblem());
}

GlfwSession::~GlfwSession() { glfwTerminate(); }

int GlfwSession::monitorCount() const {
  int count = 0;
  glfwGetMonitors(&count);
  return count;
}

WindowOptions windowOptionsFor(const Display& d) {
  WindowOptions o;
  o.title = d.name;
  o.width = d.rect.width();
  o.height = d.rect.height();
  o.fullscreen = d.fullscreen;
  o.monitor = d.monitor;
  // Windowed, the displays sit where the canvas has them: on one screen (Xvfb, a desktop) they
  // would otherwise open on top of each other, and a window's pixels read back from the X server
  // are only its own where no other window covers it.
  o.x = d.rect.x0;
  o.y = d.rect.y0;
  return o;
}

std::unique_ptr<Presenter> makeGlfwPresenter(GlfwSession& /*session*/, const WindowOptions& o) {
  return std::make_unique<GlfwPresenter>(o);
}

}  // namespace wall
