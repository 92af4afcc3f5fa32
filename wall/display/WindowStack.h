#pragma once
// The displays of a service wall process that several jobs share, each in its window (issue 37;
// docs/design.md, "Several jobs on one wall"). Each job's node presents its window's parts of the
// process's displays through the layers of its Window: CPU images, no GL. One thread, the
// process's presenting (main) thread, composes the displays that changed (compose()) and shows
// them on their presenters; the jobs' threads never touch GL and never wait for a presentation.
//
// What a display shows: the background, then each window's last swapped part, in stacking order
// (higher on top; among equal orders the newest on top, so windows added without one stack in
// the order they came; docs/service.md, "The wall's control page": raise). A window's frame becomes
// visible only whole: its layers stage their frames at swap() and the last of them to swap commits
// them all at once, so no composition shows a frame of a window on one display and another frame on
// the next (the swap barrier keeps the processes together; this keeps a process's displays
// together). A window that goes leaves the displays at the next composition. What a layer reads
// back is its own part as it last presented it (the job's capture), not what covers it.
//
// Threading: a Window and its layers belong to one job's thread (but setOrder() may come from any
// thread while the window lives); compose(), frame() and takeChanges() to one presenting thread;
// the stack's lock is held only to trade buffers and orders, never while composing.
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <vector>

#include "dfb/Tile.h"
#include "wall/display/Presenter.h"
#include "wall/image/Image.h"

namespace wall {

class WindowStack {
 public:
  struct Size {
    int width = 0, height = 0;
  };
  // `displays`: this process's displays (in layout.displaysOfProcess order); `background`: RGBA8
  // as in Image. `changed` runs (unlocked, on the calling job's thread) whenever a display needs
  // composing again: a window's frame committed, a window came or went.
  WindowStack(std::vector<Size> displays, std::uint32_t background,
              std::function<void()> changed = {});
  ~WindowStack();
  WindowStack(const WindowStack&) = delete;
  WindowStack& operator=(const WindowStack&) = delete;

  class Window;
  // A job's window on top of the others: `parts[d]` is its part of display d in the display's
  // coordinates (empty: it misses d; else inside d). Every display is composed again when the
  // first window comes (the background replaces whatever was shown). The window must go before
  // the stack does. `tag`: what topAt() answers for the window (the service: its job's session).
  // With an `order`: at that stacking order instead, above every window of a lower or equal order
  // and beneath those of a higher one (a job's Start, or a Raise that came first).
  static constexpr std::uint64_t kOnTop = ~std::uint64_t{0};
  std::unique_ptr<Window> add(const std::vector<dfb::Region>& parts, std::uint64_t tag = 0,
                              std::uint64_t order = kOnTop);

  // The presenting thread: composes every display that changed since the last call into its
  // frame() (each pixel written once: the top window's part covering it, or the background) and
  // returns their indices (empty: nothing changed).
  std::vector<int> compose();
  const Image& frame(int display) const { return frames_[static_cast<size_t>(display)]; }
  // Forgets pending changes without composing (the displays show something else: the idle
  // screen). The first window to come after composes every display again.
  void dropChanges();
  std::size_t windows() const;
  // The tag of the top window covering pixel (x, y) of display `display` (where a key or a click
  // on it goes), 0 where none does. Any thread.
  std::uint64_t topAt(int display, int x, int y) const;

 private:
  class Layer;
  struct Shown {
    dfb::Region part;  // on display `display`
    int display = 0;
    std::shared_ptr<const Image> pixels;  // the last committed frame (null: none yet)
    std::shared_ptr<Image> staged;        // swapped, waiting for the window's other layers
    std::shared_ptr<Image> spare;         // a buffer for the layer's next frame
  };
  struct Entry {
    std::vector<Shown> layers;  // the window's non-empty parts
    int staged = 0;             // layers that swapped since the last commit
    std::uint64_t order = 0;    // stacking order
    std::uint64_t tag = 0;
  };
  std::unique_ptr<Window> addLocked(Entry entry, std::uint64_t order);
  void remove(Entry* entry);
  void setOrder(Entry* entry, std::uint64_t order);
  void placeLocked(std::list<Entry>::iterator entry);  // by its order, above its equals
  void markAll();

  std::vector<Size> sizes_;
  std::uint32_t background_;
  std::function<void()> changed_;
  mutable std::mutex mutex_;
  std::list<Entry> windows_;  // bottom first (ascending order)
  std::vector<char> dirty_;   // by display
  std::vector<Image> frames_;
};

// A job's window: one presenter per display it touches, for the job's node.
class WindowStack::Window {
 public:
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  // In the order of the displays (those the window misses left out).
  std::vector<Presenter*> presenters() const;
  // The window takes stacking order `order` (the window manager's raise): above every window of
  // a lower or equal order. The displays it touches are composed again, without a new frame.
  void setOrder(std::uint64_t order);
  // What the window shows now on each display it touches: its last committed frame's parts
  // (null pixels before the first), held so that no later frame writes into them.
  struct Shown {
    int display = 0;   // index among the stack's displays
    dfb::Region part;  // in that display's coordinates
    std::shared_ptr<const Image> pixels;
  };
  std::vector<Shown> shown() const;

 private:
  friend class WindowStack;
  Window(WindowStack& stack, Entry& entry);
  WindowStack& stack_;
  Entry& entry_;
  std::vector<std::unique_ptr<Layer>> layers_;
};

// Writes the display frame: every pixel the top layer's that covers it, else the background,
// by spans of rows (bands of rows the same layers cover, each cut where a layer begins or ends).
// `layers` bottom first; each pixel image is its part's size. Shared by WindowStack and
// bench/composition_bench.
struct ComposedLayer {
  dfb::Region part;
  const Image* pixels = nullptr;
};
void composeLayers(Image& frame, std::uint32_t background,
                   const std::vector<ComposedLayer>& layers);

}  // namespace wall
