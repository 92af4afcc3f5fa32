#include "wall/display/DisplayPresenters.h"

#include "wall/display/OsmesaPresenter.h"

namespace wall {

std::vector<Presenter*> DisplayPresenters::list() const {
  std::vector<Presenter*> out;
  for (const auto& p : owned) out.push_back(p.get());
  return out;
}

std::unique_ptr<DisplayPresenters> makeDisplayPresenters(const Layout& layout, int process,
                                                         bool offscreen) {
  auto presenters = std::make_unique<DisplayPresenters>();
  if (!offscreen) presenters->glfw.emplace();
  for (int d : layout.displaysOfProcess(process)) {
    const Display& display = layout.displays[static_cast<size_t>(d)];
    presenters->owned.push_back(
        offscreen ? makeOsmesaPresenter(display.rect.width(), display.rect.height())
                  : makeGlfwPresenter(*presenters->glfw, windowOptionsFor(display)));
  }
  return presenters;
}

}  // namespace wall
