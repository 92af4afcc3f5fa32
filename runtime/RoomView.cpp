#include "runtime/RoomView.h"

namespace runtime {
namespace {

renderers::Vec3 toVec3(const wall::Point3& p) {
  return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}

}  // namespace

std::shared_ptr<const renderers::RoomView> roomView(const wall::Layout& layout) {
  if (!layout.inRoom()) return nullptr;
  auto room = std::make_shared<renderers::RoomView>();
  for (const wall::Display& d : layout.displays) {
    const wall::Screen& s = d.screen.value();
    room->screens.push_back({d.rect, toVec3(s.bottomLeft), toVec3(s.bottomRight), toVec3(s.topLeft),
                             toVec3(wall::eyePosition(*layout.viewer, d.eye))});
  }
  return room;
}

}  // namespace runtime
