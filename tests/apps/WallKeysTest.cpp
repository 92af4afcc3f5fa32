// A service wall's keys and mouse over a job's window as the job's steering requests
// (apps/WallKeys.h): the page's drags and wheel, the single wall's keys, always in checkRequest's
// ranges.
#include <gtest/gtest.h>

#include <cmath>

#include "apps/Steering.h"
#include "apps/WallKeys.h"

namespace app {
namespace {

using wall::service::WindowInput;

WindowInput drag(int dx, int dy, bool pan = false) {
  WindowInput in;
  in.kind = WindowInput::kDrag;
  in.dx = dx;
  in.dy = dy;
  in.pan = pan;
  return in;
}

TEST(WallInput, ADragAcrossTheWindowOrbitsHalfATurnAsOnThePage) {
  const auto r = requestForInput(drag(200, 0), 200, 100);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, SteeringRequest::kCamera);
  EXPECT_EQ(r->fields, SteeringRequest::kOrbit);
  EXPECT_FLOAT_EQ(r->orbit, -180.0f);
  EXPECT_EQ(checkRequest(*r), "");
}

TEST(WallInput, APanDragMovesAViewHeightPerWindowHeight) {
  const auto r = requestForInput(drag(50, -100, true), 200, 100);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->fields, SteeringRequest::kPan);
  EXPECT_FLOAT_EQ(r->pan[0], -0.5f);
  EXPECT_FLOAT_EQ(r->pan[1], -1.0f);
}

TEST(WallInput, TheWheelDolliesAsPlusAndKeysAreTheWallsKeys) {
  WindowInput wheel;
  wheel.kind = WindowInput::kScroll;
  wheel.dy = 2;
  const auto r = requestForInput(wheel, 200, 100);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->fields, SteeringRequest::kDolly);
  EXPECT_FLOAT_EQ(r->dolly, kKeyDollyFactor * kKeyDollyFactor);
  WindowInput key;
  key.key = WindowInput::kRight;
  const auto k = requestForInput(key, 200, 100);
  ASSERT_TRUE(k);
  EXPECT_EQ(k->fields, SteeringRequest::kOrbit);
  EXPECT_FLOAT_EQ(k->orbit, kKeyOrbitDegrees);
}

TEST(WallInput, HugeMovesStayInRangeAndNothingComesOfEmptyOrUnknownEvents) {
  for (const auto& in :
       {drag(wall::service::kMaxInputMove, 0), drag(0, -wall::service::kMaxInputMove, true)}) {
    const auto r = requestForInput(in, 1, 1);
    ASSERT_TRUE(r);
    EXPECT_EQ(checkRequest(*r), "");
  }
  WindowInput wheel;
  wheel.kind = WindowInput::kScroll;
  wheel.dy = -wall::service::kMaxInputMove;
  const auto far = requestForInput(wheel, 10, 10);
  ASSERT_TRUE(far);
  EXPECT_EQ(checkRequest(*far), "");
  EXPECT_FALSE(requestForInput(drag(0, 0), 10, 10));
  WindowInput key;
  key.key = WindowInput::kKeyCount;
  EXPECT_FALSE(requestForInput(key, 10, 10));
  key.kind = 9;
  EXPECT_FALSE(requestForInput(key, 10, 10));
  EXPECT_FALSE(requestForInput(drag(5, 0), 0, 10));
}

}  // namespace
}  // namespace app
