#pragma once
// Something that shows a display's frames: a window (wall/display/GlfwPresenter.h) or an offscreen
// GL drawable (wall/display/OsmesaPresenter.h). Only wall ranks construct presenters, so only they
// touch GL.
//
// Threading: a presenter is used from the thread that made it (its GL context is made current
// there on every call). Several presenters may live on one thread (a process driving several
// displays); each call switches to its own context.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "dfb/Tile.h"
#include "wall/image/Image.h"

namespace wall {

// Keys an operator pressed in a display's window, for a wall with a keyboard attached: the app
// turns them into camera changes and a graceful stop.
enum class WallKey { Left, Right, Up, Down, Plus, Minus, Escape };

// An operator's key or mouse event in a display's window, where the cursor was: a key pressed,
// a drag (the cursor moved with a button held: `x`, `y` where the button went down, so the whole
// drag belongs to what was under it; `dx`, `dy` pixels moved since the last event; `pan`: the
// right button or Shift held) or the wheel (`dy` notches, up positive). Display pixels, row 0 at
// the top.
struct WallInput {
  enum class Kind { Key, Drag, Scroll };
  Kind kind = Kind::Key;
  WallKey key = WallKey::Escape;
  int x = 0, y = 0;
  int dx = 0, dy = 0;
  bool pan = false;
};

class Presenter {
 public:
  virtual ~Presenter() = default;

  // A frame is shown in four steps, so a wall can overlap the first with the network and keep
  // the last one together across displays (Tide's order: upload, draw, swap barrier, swap):
  //  1. beginFrame(width, height): the next frame is `width` x `height` RGBA8 pixels (R in the
  //     low byte, row 0 at the top); its texture is made that size (contents undefined).
  //  2. upload(frame, stride, rect), any number of times: copies `rect` of the frame into the
  //     texture, `frame` pointing at pixel (0, 0) of rows `stride` pixels apart. The rects of
  //     one frame must together cover it (each pixel once is enough).
  //  3. draw(): draws the texture at 1:1 in the top-left corner of the back buffer (a GL
  //     texture drawn by a full-screen triangle with texelFetch, never scaled) and waits until
  //     it is drawn (glFinish), so the swap costs no rendering. Nothing new is visible yet.
  //  4. swap(): makes what draw() drew visible (GLFW: swaps the buffers; OSMesa draws into its
  //     buffer directly, which has no front buffer, so this does nothing more).
  // The texture keeps its contents until the next upload, so upload for frame F+1 only after
  // draw() of F. Throws base::Error on a GL failure.
  virtual void beginFrame(int width, int height) = 0;
  void upload(const std::uint32_t* frame, int stride, const dfb::Region& rect) {
    uploadAt(frame + static_cast<std::ptrdiff_t>(rect.y0) * stride + rect.x0, stride, rect);
  }
  // Step 2 with `first` pointing at the pixel that goes to (rect.x0, rect.y0): the source need
  // not be the frame itself (a window's part of a display, wall/display/WindowPresenter.h).
  virtual void uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) = 0;
  virtual void draw() = 0;
  virtual void swap() = 0;
  // All four steps for a whole frame at once.
  void present(const std::uint32_t* rgba8, int width, int height) {
    beginFrame(width, height);
    upload(rgba8, width, {0, 0, width, height});
    draw();
    swap();
  }

  // What the last swap() put on the drawable (the frame's size, from the top-left): OSMesa
  // reads its buffer with glReadPixels, a window asks the X server for its pixels. This is what
  // the display shows, not a copy of the input. Slow (a full readback); for tests and captures.
  virtual Image readBack() = 0;

  // The user closed the window (always false offscreen).
  virtual bool closeRequested() const { return false; }
  // Keys pressed (and repeated while held), drags and wheel turns since the last call, in order
  // (none offscreen). Bounded: events nobody takes are dropped past a few hundred.
  virtual std::vector<WallInput> takeInput() { return {}; }
  // The keys of takeInput() (the rest is dropped): for a wall whose keys steer one job.
  std::vector<WallKey> takeKeys() {
    std::vector<WallKey> keys;
    for (const WallInput& in : takeInput())
      if (in.kind == WallInput::Kind::Key) keys.push_back(in.key);
    return keys;
  }
  // Handles window events (keys, close) without presenting: a wall waiting for its next frame
  // still hears its keyboard.
  virtual void pollEvents() {}

  // For logs: the kind of presenter and the GL_VERSION / GL_RENDERER strings of its context.
  virtual std::string describe() const = 0;
};

}  // namespace wall
