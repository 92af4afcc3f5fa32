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

SteeringRequest timeRequest(std::uint64_t id, std::uint32_t fields) {
  SteeringRequest r;
  r.kind = SteeringRequest::kTime;
  r.fields = fields;
  r.id = id;
  return r;
}

TEST(FrameDirector, ASeriesPlaysOneStepAFrameLoopingEachANewEpoch) {
  DirectorOptions o = still(2);
  o.timeSteps = 3;
  FrameDirector d(o);
  std::vector<std::uint32_t> steps, epochs;
  for (std::uint32_t f = 1; f <= 5; ++f) {
    const FrameOrder order = d.next(f, {});
    steps.push_back(order.view.timeStep);
    epochs.push_back(order.frame.epoch);
    EXPECT_FALSE(d.converged()) << "a playing series never converges";
  }
  EXPECT_EQ(steps, (std::vector<std::uint32_t>{0, 1, 2, 0, 1}));
  EXPECT_EQ(epochs, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
}

TEST(FrameDirector, AtFpsAStepLastsItsPeriodAndNeverSkips) {
  DirectorOptions o = still(0);
  o.timeSteps = 10;
  o.fps = 10;  // 100 ms a step
  std::chrono::steady_clock::time_point now{};
  o.now = [&now] { return now; };
  FrameDirector d(o);
  using std::chrono::milliseconds;
  EXPECT_EQ(d.next(1, {}).view.timeStep, 0u);
  now += milliseconds(60);
  EXPECT_EQ(d.next(2, {}).view.timeStep, 0u);  // not due yet
  now += milliseconds(50);
  EXPECT_EQ(d.next(3, {}).view.timeStep, 1u);
  now += milliseconds(1000);  // frames fell behind: the next step, not ten steps on
  EXPECT_EQ(d.next(4, {}).view.timeStep, 2u);
  EXPECT_EQ(d.next(5, {}).view.timeStep, 2u);  // from now on the period again
  now += milliseconds(100);
  EXPECT_EQ(d.next(6, {}).view.timeStep, 3u);
}

TEST(FrameDirector, PauseStepAndSeek) {
  DirectorOptions o = still(2);
  o.timeSteps = 4;
  FrameDirector d(o);
  d.next(1, {});
  d.next(2, {});  // step 1
  SteeringRequest pause = timeRequest(1, SteeringRequest::kPlay);
  pause.play = 0;
  EXPECT_EQ(d.next(3, {pause}).view.timeStep, 1u);
  EXPECT_FALSE(d.playing());
  EXPECT_TRUE(d.converged()) << "paused, the step's samples reached";
  EXPECT_EQ(d.next(4, {}).view.timeStep, 1u);
  SteeringRequest back = timeRequest(2, SteeringRequest::kStepBy);
  back.stepBy = -2;  // wraps around
  EXPECT_EQ(d.next(5, {back}).view.timeStep, 3u);
  SteeringRequest seek = timeRequest(3, SteeringRequest::kSeek | SteeringRequest::kPlay);
  seek.seek = 2;
  seek.play = 1;
  EXPECT_EQ(d.next(6, {seek}).view.timeStep, 2u) << "a seek shows its step a frame";
  EXPECT_EQ(d.next(7, {}).view.timeStep, 3u);
  SteeringRequest past = timeRequest(4, SteeringRequest::kSeek);
  past.seek = 4;
  EXPECT_EQ(d.next(8, {past}).view.timeStep, 0u);
  const std::vector<std::string> errors = d.takeErrors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("step 4 is past the series' 4 steps"), std::string::npos) << errors[0];
}

TEST(FrameDirector, ATimeRequestWithoutASeriesIsAnError) {
  FrameDirector d(still(2));
  SteeringRequest play = timeRequest(1, SteeringRequest::kPlay);
  play.play = 1;
  EXPECT_EQ(d.next(1, {play}).view.timeStep, 0u);
  const std::vector<std::string> errors = d.takeErrors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("no time series"), std::string::npos) << errors[0];
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

TEST(CameraPath, KeyframesMayHoldATimeStep) {
  const std::string file = writeFile(
      "fps = 10\n[[keyframe]]\ntime = 0\nposition = [0, 0, -10]\nlook_at = [0, 0, 0]\n"
      "[[keyframe]]\ntime = 0.5\nposition = [5, 0, -10]\nlook_at = [0, 0, 0]\nstep = 3\n"
      "[[keyframe]]\ntime = 1\nposition = [10, 0, -10]\nlook_at = [0, 0, 0]\nstep = 1\n");
  const CameraPath path = CameraPath::load(file, {}, 4);
  EXPECT_FALSE(path.stepAt(1).has_value());  // before any keyframe names one
  EXPECT_EQ(path.stepAt(6).value_or(99), 3u);
  EXPECT_EQ(path.stepAt(10).value_or(99), 3u);  // held, not interpolated
  EXPECT_EQ(path.stepAt(11).value_or(99), 1u);
  DirectorOptions o = still(0);
  o.timeSteps = 4;
  o.path = [&path](std::uint32_t f) { return path.at(f); };
  o.pathStep = [&path](std::uint32_t f) { return path.stepAt(f); };
  FrameDirector d(o);
  EXPECT_EQ(d.next(1, {}).view.timeStep, 0u);
  EXPECT_EQ(d.next(2, {}).view.timeStep, 1u);  // playing until the path names a step
  EXPECT_EQ(d.next(6, {}).view.timeStep, 3u);
  EXPECT_EQ(d.next(7, {}).view.timeStep, 3u);
  try {
    CameraPath::load(file, {}, 2);
    FAIL() << "a step past the series was accepted";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe #2.step: must be from 0 to 1"),
              std::string::npos)
        << e.what();
  }
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
