#pragma once
// The presenters of one wall process's displays: OSMesa offscreen, or a GLFW window per display
// (on the monitor and in the mode the layout asks for). Only wall processes make them, so only
// they start GL. Shared by the single-job wall ranks, `dfbwall serve` and the API's wall ranks.
#include <memory>
#include <optional>
#include <vector>

#include "wall/display/GlfwPresenter.h"
#include "wall/display/Presenter.h"
#include "wall/layout/Layout.h"

namespace wall {

struct DisplayPresenters {
  std::optional<GlfwSession> glfw;  // windows only; outlives the windows
  std::vector<std::unique_ptr<Presenter>> owned;
  // The same, not owned, in layout.displaysOfProcess order (what WallNode takes).
  std::vector<Presenter*> list() const;
};

// Throws base::Error when a window or context cannot be made.
std::unique_ptr<DisplayPresenters> makeDisplayPresenters(const Layout& layout, int process,
                                                         bool offscreen);

}  // namespace wall
