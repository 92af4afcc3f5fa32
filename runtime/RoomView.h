#pragma once
// A layout's screens in the room (wall/layout/Room.h) as the renderers' camera model
// (renderers/RoomView.h): each display's canvas pixels, corners and eye.
#include <memory>

#include "renderers/RoomView.h"
#include "wall/layout/Layout.h"

namespace runtime {

// Null when the layout places no screens (one pinhole image over the canvas, as without it).
std::shared_ptr<const renderers::RoomView> roomView(const wall::Layout& layout);

}  // namespace runtime
