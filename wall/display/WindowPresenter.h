#pragma once
// A display of a service wall seen by a job in a window (wall/layout/Window.h): the job's node
// presents the window's part of the display (its size, from (0, 0)); this shows the display's
// whole frame, that part at its offset and the background everywhere else, on the display's own
// presenter. What it reads back is the part only: a job's captures are its window's pixels.
#include <cstdint>

#include "dfb/Tile.h"
#include "wall/display/Presenter.h"
#include "wall/image/Image.h"

namespace wall {

class WindowPresenter : public Presenter {
 public:
  // `display`: the presenter of a display `width` x `height`; `part`: the window's part of it,
  // in the display's coordinates (non-empty, inside it); `background`: RGBA8 as in Image.
  WindowPresenter(Presenter& display, int width, int height, const dfb::Region& part,
                  std::uint32_t background);

  // The display's whole frame: the background only (a display the window does not touch).
  static void presentBackground(Presenter& display, int width, int height,
                                std::uint32_t background);

  void beginFrame(int width, int height) override;
  void uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) override;
  void draw() override { display_.draw(); }
  void swap() override { display_.swap(); }
  Image readBack() override;
  bool closeRequested() const override { return display_.closeRequested(); }
  std::vector<WallInput> takeInput() override { return display_.takeInput(); }
  void pollEvents() override { display_.pollEvents(); }
  std::string describe() const override { return display_.describe(); }

 private:
  Presenter& display_;
  int width_, height_;
  dfb::Region part_;
  Image background_;  // the display's size, every pixel the background
};

}  // namespace wall
