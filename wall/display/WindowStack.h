#pragma once
// A display of a service wall that several jobs share, each in its window (issue 37; see
// docs/design.md, "Several jobs on one wall"): each job's node presents its window's part of the
// display through its own layer, and the display shows the background with every layer's last
// presented part on it, in stacking order (higher on top; the newest on top when the orders are
// equal, or not given; docs/service.md, "The wall's control page": raise). A layer's frame
// becomes visible at its swap(), after the job's swap barrier, and never waits for another
// layer: the others show their last swapped part. A layer that goes away leaves the display at
// once (what was under it shows again). What a layer reads back is its own part as it presented
// it (the job's capture), not what covers it.
//
// Threading: each layer is used by one job's thread; the display's presenter is used under the
// stack's lock only, at a layer's swap (so a layer's draw() does nothing: composing after the
// barrier keeps one job's barrier from waiting on another's lock).
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>

#include "dfb/Tile.h"
#include "wall/display/Presenter.h"
#include "wall/image/Image.h"

namespace wall {

class WindowStack {
 public:
  // `display`: the presenter of a display `width` x `height`; `background`: RGBA8 as in Image.
  WindowStack(Presenter& display, int width, int height, std::uint32_t background);
  ~WindowStack();
  WindowStack(const WindowStack&) = delete;
  WindowStack& operator=(const WindowStack&) = delete;

  // A job's part of this display (in its coordinates, non-empty, inside it), on top of the
  // layers there now, or at stacking order `order` (above those of a lower or equal order). The
  // layer must go before the stack does; when it goes, the display is presented again without it.
  std::unique_ptr<Presenter> add(const dfb::Region& part);
  std::unique_ptr<Presenter> add(const dfb::Region& part, std::uint64_t order);
  // A layer of this stack takes stacking order `order`; the display is presented again.
  void setOrder(const Presenter& layer, std::uint64_t order);
  // The background and every layer's last swapped part, in order, on the display.
  void present();
  std::size_t layers() const;

 private:
  class Layer;
  struct Shown {
    dfb::Region part;
    std::uint64_t order = 0;
    Image pixels;      // the part's size; what the layer last swapped
    bool any = false;  // it swapped a frame yet (else it shows nothing)
  };
  void presentLocked();
  void remove(const Shown* shown);
  void placeLocked(std::list<Shown>::iterator shown);  // by its order, above its equals

  Presenter& display_;
  int width_, height_;
  std::uint32_t background_;
  mutable std::mutex mutex_;
  std::list<Shown> shown_;  // bottom first (ascending order)
  Image frame_;             // the display's composed frame
};

}  // namespace wall
