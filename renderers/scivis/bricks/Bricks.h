#pragma once
// A data-parallel brick of a scivis scene, as every part names it: planning (BrickPlan.h), loading
// its data (BrickLoad.h) and the directory every rank agrees on (BrickExchange.h).
#include "renderers/scivis/scene/Box.h"

namespace renderers::scivis {

struct BrickPlan {
  int id = 0;
  Box3 bounds;  // bricks tile the domain; camera rays are clipped to them
};

}  // namespace renderers::scivis
