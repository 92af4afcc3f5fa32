#pragma once
// Offscreen presenting through OSMesa (llvmpipe): an OpenGL 3.3 core context drawing into a
// buffer in memory, for tests, CI and --offscreen walls. The same GL drawing as a window.
#include <memory>

#include "wall/display/Presenter.h"

namespace wall {

// A presenter with a `width` x `height` offscreen drawable (the display's size). A frame of
// another size is drawn into a drawable resized to match. Throws base::Error when OSMesa cannot
// make a 3.3 core context.
std::unique_ptr<Presenter> makeOsmesaPresenter(int width, int height);

}  // namespace wall
