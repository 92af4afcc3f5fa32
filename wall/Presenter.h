#pragma once
// Something that shows a display's frames: a window (wall/GlfwPresenter.h) or an offscreen GL
// drawable (wall/OsmesaPresenter.h). Only wall ranks construct presenters, so only they touch GL.
//
// Threading: a presenter is used from the thread that made it (its GL context is made current
// there on every call). Several presenters may live on one thread (a process driving several
// displays); each call switches to its own context.
#include <cstdint>
#include <string>
#include <vector>

#include "wall/Image.h"

namespace wall {

// Keys an operator pressed in a display's window, for a wall with a keyboard attached: the app
// turns them into camera changes and a graceful stop.
enum class WallKey { Left, Right, Up, Down, Plus, Minus, Escape };

class Presenter {
 public:
  virtual ~Presenter() = default;

  // Shows one frame of `width` x `height` RGBA8 pixels (R in the low byte, row 0 at the top) at
  // 1:1 in the top-left corner of the drawable: a GL texture drawn by a full-screen quad with
  // texelFetch, never scaled. Returns once the frame is drawn (OSMesa: rendered into its buffer;
  // GLFW: buffers swapped). Throws wall::Error on a GL failure.
  virtual void present(const std::uint32_t* rgba8, int width, int height) = 0;

  // What the last present() put on the drawable (the frame's size, from the top-left): OSMesa
  // reads its buffer with glReadPixels, a window asks the X server for its pixels. This is what
  // the display shows, not a copy of the input. Slow (a full readback); for tests and captures.
  virtual Image readBack() = 0;

  // The user closed the window (always false offscreen).
  virtual bool closeRequested() const { return false; }
  // Keys pressed (and repeated while held) since the last call, in order (none offscreen).
  virtual std::vector<WallKey> takeKeys() { return {}; }
  // Handles window events (keys, close) without presenting: a wall waiting for its next frame
  // still hears its keyboard.
  virtual void pollEvents() {}

  // For logs: the kind of presenter and the GL_VERSION / GL_RENDERER strings of its context.
  virtual std::string describe() const = 0;
};

}  // namespace wall
