#pragma once
// Window presenting through GLFW: one window per display, windowed or fullscreen on a chosen
// monitor, drawing frames with the same GL code as the offscreen presenter. Needs an X display
// (a real one, or xvfb-run in tests). GLFW wants its calls on the main thread: make the session
// and the presenters there, and present from there.
#include <memory>
#include <string>

#include "wall/display/Presenter.h"
#include "wall/layout/Layout.h"

namespace wall {

// GLFW's library state (glfwInit ... glfwTerminate), held by the caller instead of a global.
// Outlives every presenter made with it. Throws base::Error when GLFW cannot start (no display).
class GlfwSession {
 public:
  GlfwSession();
  ~GlfwSession();
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
  int monitorCount() const;
};

struct WindowOptions {
  std::string title;  // the display's name
  int width = 0, height = 0;
  bool fullscreen = false;  // on monitor `monitor`, at its video mode closest to width x height
  int monitor = 0;          // index into glfwGetMonitors(); 0 is the primary
  bool vsync = false;       // swap interval 1; off by default: the wall's swap barrier paces frames
  int x = -1, y = -1;       // windowed: top-left on the screen; negative lets the system choose
};

// The options layout display `d` asks for (position left to the window system).
WindowOptions windowOptionsFor(const Display& d);

// Opens the window; throws base::Error naming the display when GLFW cannot (no such monitor, no
// OpenGL 3.3 core context). Its readBack() reads what the X server shows in the window
// (XGetImage; opaque), so the window must be wholly on screen and unobscured for that.
std::unique_ptr<Presenter> makeGlfwPresenter(GlfwSession& session, const WindowOptions& options);

}  // namespace wall
