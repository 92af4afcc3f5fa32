// Render rank 0's per-frame decisions (apps/FrameDirector.h) and camera paths (apps/CameraPath.h):
// which camera and settings a frame gets, when a new accumulation epoch starts, when a still
// wall has converged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "apps/CameraPath.h"
#include "apps/FrameDirector.h"
#include "base/Error.h"

namespace app {
namespace {

using renderers::CameraDesc;
using renderers::Vec3;

DirectorOptions still(std::int64_t maxSpp) {
  DirectorOptions d;
  d.initial.camera.position = {0, 0, -5};
  d.initial.spp = 2;
  d.maxSpp = maxSpp;
  return d;
}

bool same(const CameraDesc& a, const CameraDesc& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

SteeringRequest camera(std::uint64_t id) {
  SteeringRequest r;
  r.kind = SteeringRequest::kCamera;
  r.id = id;
  return r;
}

TEST(FrameDirector, AStillCameraKeepsItsEpochAndConvergesAtTheBudget) {
  FrameDirector d(still(6));
  for (std::uint32_t f = 1; f <= 3; ++f) {
    EXPECT_FALSE(d.converged());
    const FrameOrder o = d.next(f, {});
    EXPECT_EQ(o.frame.frameId, f);
    EXPECT_EQ(o.frame.epoch, 0u);
    EXPECT_EQ(o.requestId, 0u);
  }
  EXPECT_EQ(d.epochSpp(), 6);
  EXPECT_TRUE(d.converged());
}

TEST(FrameDirector, AMovedWindowAccumulatesAgainFromEpochZero) {
  FrameDirector d(still(4));
  d.next(1, {});
  SteeringRequest dolly = camera(1);
  dolly.fields = SteeringRequest::kDolly;
  dolly.dolly = 2;
  d.next(2, {dolly});  // a new epoch, converged after its budget
  d.next(3, {});
  EXPECT_TRUE(d.converged());
  EXPECT_EQ(d.epoch(), 1u);
  // A new frame buffer (the window moved): the next frame is the first of epoch 0, as a run's.
  d.restartAccumulation();
  const FrameOrder o = d.next(4, {});
  EXPECT_EQ(o.frame.frameId, 4u);
  EXPECT_EQ(o.frame.epoch, 0u);
  EXPECT_EQ(d.epochSpp(), 2);
  EXPECT_FALSE(d.converged());
  d.next(5, {});
  EXPECT_EQ(d.epoch(), 0u);
  EXPECT_TRUE(d.converged());
}

// `dfbwall show`: a sequence of three pictures, one sample each; converged only once the next
// frame would show the picture the last one showed.
TEST(FrameDirector, ASequenceConvergesWhenTheNextFrameShowsTheSamePicture) {
  DirectorOptions o = still(1);
  o.content = [](std::uint32_t frameId) { return std::min<std::uint32_t>(frameId, 3); };
  FrameDirector d(o);
  for (std::uint32_t f = 1; f <= 2; ++f) {
    d.next(f, {});
    EXPECT_FALSE(d.converged()) << "frame " << f;
  }
  d.next(3, {});
  EXPECT_TRUE(d.converged());
}

TEST(FrameDirector, TheOrbitIsTheOldPerFrameOrbitAndNeverConverges) {
  DirectorOptions o = still(2);
  o.orbitDegrees = 7.5f;
  FrameDirector d(o);
  std::uint32_t lastEpoch = 0;
  for (std::uint32_t f = 1; f <= 5; ++f) {
    const FrameOrder order = d.next(f, {});
    EXPECT_TRUE(same(order.view.camera, renderers::orbitCamera(o.initial.camera, 7.5f * (f - 1))));
    if (f > 1) {
      EXPECT_GT(order.frame.epoch, lastEpoch);  // every frame its own epoch
    }
    lastEpoch = order.frame.epoch;
    EXPECT_FALSE(d.converged());
  }
}

TEST(FrameDirector, ACameraRequestStartsANewEpochFromWhatIsShown) {
  FrameDirector d(still(4));
  d.next(1, {});
  d.next(2, {});
  ASSERT_TRUE(d.converged());
  SteeringRequest r = camera(9);
  r.fields = SteeringRequest::kFov | SteeringRequest::kDolly;
  r.fov = 60;
  r.dolly = 2;
  r.receivedNs = 123;
  r.presentedAtArrival = 1;
  const FrameOrder o = d.next(3, {r});
  EXPECT_EQ(o.frame.epoch, 1u);
  EXPECT_EQ(o.requestId, 9u);
  EXPECT_EQ(o.requestNs, 123);
  EXPECT_EQ(o.presentedAtRequest, 1);
  EXPECT_EQ(o.view.camera.fovY, 60.0f);
  EXPECT_EQ(o.view.camera.position.z, -2.5f);  // half the distance to the look-at point
  EXPECT_EQ(d.epochSpp(), 2);
  EXPECT_FALSE(d.converged());
  EXPECT_EQ(d.lastRequest(), 9u);
  EXPECT_EQ(d.lastRequestFrame(), 3u);
}

TEST(FrameDirector, AnUnusableCameraIsRefusedWithAnError) {
  FrameDirector d(still(4));
  d.next(1, {});
  SteeringRequest r = camera(3);
  r.fields = SteeringRequest::kLookAt;
  r.lookAt = {0, 0, -5};  // the position itself
  const FrameOrder o = d.next(2, {r});
  EXPECT_EQ(o.frame.epoch, 0u);
  EXPECT_EQ(o.view.camera.lookAt.z, 0.0f);
  const auto errors = d.takeErrors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("request 3"), std::string::npos);
}

TEST(FrameDirector, SettingsStartANewEpochCapturesDoNot) {
  FrameDirector d(still(100));
  d.next(1, {});
  SteeringRequest capture;
  capture.kind = SteeringRequest::kCapture;
  const FrameOrder c = d.next(2, {capture});
  EXPECT_EQ(c.frame.epoch, 0u);
  EXPECT_EQ(c.captureSequence, 1u);
  SteeringRequest s;
  s.kind = SteeringRequest::kSettings;
  s.fields = SteeringRequest::kSpp | SteeringRequest::kExposure;
  s.spp = 8;
  s.exposure = 2;
  const FrameOrder o = d.next(3, {s, capture});
  EXPECT_EQ(o.frame.epoch, 1u);
  EXPECT_EQ(o.view.spp, 8);
  EXPECT_EQ(o.view.exposure, 2.0f);
  EXPECT_EQ(o.captureSequence, 2u);
  EXPECT_EQ(d.epochSpp(), 8);
}

TEST(SteeringRequest, ChecksRangesAndKinds) {
  SteeringRequest r = camera(1);
  EXPECT_FALSE(checkRequest(r).empty());  // no field
  r.fields = SteeringRequest::kFov;
  r.fov = 45;
  EXPECT_TRUE(checkRequest(r).empty());
  r.fov = std::nanf("");
  EXPECT_FALSE(checkRequest(r).empty());
  r.fov = 45;
  r.fields |= SteeringRequest::kSpp;  // a settings field in a camera request
  EXPECT_FALSE(checkRequest(r).empty());
}

std::string writeFile(const std::string& text) {
  char name[] = "/tmp/camera-path-XXXXXX";
  const int fd = mkstemp(name);
  FILE* f = fdopen(fd, "w");
  std::fputs(text.c_str(), f);
  std::fclose(f);
  return name;
}

TEST(CameraPath, InterpolatesBetweenKeyframesAndHoldsAfterTheLast) {
  const std::string file = writeFile(
      "fps = 10\n[[keyframe]]\ntime = 0\nposition = [0, 0, -10]\nlook_at = [0, 0, 0]\n"
      "[[keyframe]]\ntime = 1\nposition = [10, 0, -10]\nlook_at = [0, 0, 0]\nfov = 60\n");
  CameraDesc scene;
  scene.fovY = 40;
  const CameraPath path = CameraPath::load(file, scene);
  EXPECT_EQ(path.at(1).position.x, 0.0f);
  EXPECT_EQ(path.at(1).fovY, 40.0f);             // the scene's, for the first keyframe
  EXPECT_FLOAT_EQ(path.at(6).position.x, 5.0f);  // frame 6: t = 0.5 s
  EXPECT_FLOAT_EQ(path.at(6).fovY, 50.0f);
  EXPECT_TRUE(same(path.at(11), path.at(500)));  // holds after the last keyframe
  std::remove(file.c_str());
}

TEST(CameraPath, ErrorsNameFileAndLine) {
  const std::string file = writeFile(
      "[[keyframe]]\ntime = 0\nposition = [0, 0, -10]\nlook_at = [0, 0, 0]\nup = [0, 0, 1]\n");
  try {
    CameraPath::load(file, {});
    FAIL() << "a camera looking along its up vector was accepted";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find(file + ":1:"), std::string::npos) << e.what();
  }
  std::remove(file.c_str());
}

}  // namespace
}  // namespace app
