// The data-distributed API embedded in a program: the calling thread gets its own
// floating-point mode back after rendering, the program's own TBB parallelism is not capped by a
// session, render ranks that pass different styles fail together, and errors are thrown, never
// turned into MPI_Abort.
#include <gtest/gtest.h>
#include <mpi.h>
#include <pmmintrin.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "api/DataDistributed.h"
#include "api/SceneStyle.h"
#include "api/SessionTesting.h"
#include "tests/MpiTestUtil.h"
#include "tests/api/ApiTestScene.h"

namespace {

using namespace apitest;

struct FloatMode {
  bool flushZero, denormalsZero;
};

void setFloatMode(FloatMode mode) {
  _MM_SET_FLUSH_ZERO_MODE(mode.flushZero ? _MM_FLUSH_ZERO_ON : _MM_FLUSH_ZERO_OFF);
  _MM_SET_DENORMALS_ZERO_MODE(mode.denormalsZero ? _MM_DENORMALS_ZERO_ON : _MM_DENORMALS_ZERO_OFF);
}

FloatMode floatMode() {
  return {_MM_GET_FLUSH_ZERO_MODE() == _MM_FLUSH_ZERO_ON,
          _MM_GET_DENORMALS_ZERO_MODE() == _MM_DENORMALS_ZERO_ON};
}

// What a denormal does in this thread's mode: 1e-40f * 0.5 is a denormal result (kept without
// flush-to-zero), and 1e-40f itself reads as 0 under denormals-are-zero.
bool denormalResultKept() {
  volatile float tiny = 1e-40f;
  volatile float half = tiny * 0.5f;
  return half != 0.0f;
}

dfbwall::SessionOptions options(int threads) {
  dfbwall::SessionOptions o;
  o.width = 64, o.height = 48, o.tileSize = 16, o.threads = threads, o.timeoutSeconds = 30;
  return o;
}

// Every render rank (all of MPI_COMM_WORLD) adds its slabs of 4.
void addBricks(dfbwall::Session& session, std::vector<float>& storage) {
  for (int b = testutil::worldRank(); b < 4; b += testutil::worldSize())
    session.addBrick(brick(b, 4, storage));
}

// Whether two tasks of one parallel_for run at the same time in the caller's arena: each waits
// (up to 10 s) for the other to start. Under a process-wide cap of one thread the second starts
// only after the first gave up.
bool twoTasksRunAtOnce() {
  std::atomic<int> started{0};
  std::atomic<bool> bothSeen{true};
  tbb::parallel_for(
      tbb::blocked_range<int>(0, 2, 1),
      [&](const tbb::blocked_range<int>&) {
        ++started;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (started.load() < 2 && std::chrono::steady_clock::now() < deadline)
          std::this_thread::sleep_for(std::chrono::microseconds(100));
        if (started.load() < 2) bothSeen = false;
      },
      tbb::simple_partitioner());
  return bothSeen.load();
}

TEST(ApiEmbedding, RenderFrameRestoresTheCallersFloatMode) {
  const FloatMode before = floatMode();
  std::vector<std::uint8_t> first;
  {
    dfbwall::Session session(MPI_COMM_WORLD, options(2));
    session.setStyle(style());
    session.setCamera(camera());
    std::vector<float> storage;
    addBricks(session, storage);
    // Every mode the program may be in, each kept through a frame (the first one of a scene
    // version, then accumulating ones, then a new version again).
    const FloatMode modes[] = {{false, false}, {true, true}, {true, false}, {false, true}};
    for (int round = 0; round < 2; ++round)
      for (const FloatMode mode : modes) {
        setFloatMode(mode);
        const bool newVersion = round == 1 && mode.flushZero && mode.denormalsZero;
        if (newVersion) {
          session.clearBricks();  // a new scene version: its first frame renders frame 1 again
          addBricks(session, storage);
        }
        session.renderFrame();
        const FloatMode after = floatMode();
        EXPECT_EQ(after.flushZero, mode.flushZero) << "round " << round;
        EXPECT_EQ(after.denormalsZero, mode.denormalsZero) << "round " << round;
        EXPECT_EQ(denormalResultKept(), !mode.flushZero && !mode.denormalsZero);
        if (round == 0 && !mode.flushZero && !mode.denormalsZero) first = session.image();
        // The image does not depend on the caller's mode: the new version's first frame (made
        // with the caller in another mode than frame 1 was) is frame 1's image, byte for byte.
        if (newVersion && testutil::worldRank() == 0) {
          ASSERT_FALSE(first.empty());
          EXPECT_EQ(session.image(), first);
        }
      }
    session.close();
  }
  setFloatMode(before);
}

TEST(ApiEmbedding, ThrowingRenderFrameRestoresTheCallersFloatMode) {
  dfbwall::SessionOptions o = options(2);
  o.timeoutSeconds = 20;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  session.setStyle(style());
  session.setCamera(camera());
  std::vector<float> storage;
  addBricks(session, storage);
  session.renderFrame();  // a frame rendered, so render tasks ran on this thread before
  setFloatMode({false, false});
  // "The same brick" with other bounds on rank 1: the next frame fails on every rank.
  session.clearBricks();
  dfbwall::Brick b = brick(0, 2, storage);
  if (testutil::worldRank() == 1) b.boundsHi[0] += 0.1f;
  session.addBrick(b);
  EXPECT_THROW(session.renderFrame(), std::runtime_error);
  EXPECT_FALSE(floatMode().flushZero);
  EXPECT_FALSE(floatMode().denormalsZero);
  session.close();
}

TEST(ApiEmbedding, ASessionLeavesTheProgramsTbbParallelismAlone) {
  const std::size_t cap =
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  const int concurrency = tbb::this_task_arena::max_concurrency();
  {
    dfbwall::Session session(MPI_COMM_WORLD, options(1));
    session.setStyle(style());
    session.setCamera(camera());
    std::vector<float> storage;
    addBricks(session, storage);
    session.renderFrame();
    session.renderFrame();
    // The session is alive (and its renderer with it) with one thread of its own: the program's
    // parallelism is what it was.
    EXPECT_EQ(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism), cap);
    EXPECT_EQ(tbb::this_task_arena::max_concurrency(), concurrency);
    if (concurrency >= 2) {
      EXPECT_TRUE(twoTasksRunAtOnce());
    }
    // The program's own arena too, and a cap of its own it sets while the session lives.
    tbb::task_arena mine(2);
    EXPECT_EQ(mine.max_concurrency(), 2);
    {
      tbb::global_control own(tbb::global_control::max_allowed_parallelism, 2);
      session.renderFrame();
      EXPECT_EQ(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
                2u);
    }
    session.close();
  }
  EXPECT_EQ(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism), cap);
}

// Every field of the style changes its hash (tests on one rank; the hash is what the ranks
// compare at each scene version), and the same style always gives the same hash.
TEST(ApiEmbedding, TheStyleHashCoversEveryField) {
  const dfbwall::Style base = [] {
    dfbwall::Style st = style();
    st.lights.push_back({});
    return st;
  }();
  const std::uint64_t h = dfbwall::styleHash(base);
  EXPECT_EQ(dfbwall::styleHash(base), h);
  EXPECT_EQ(dfbwall::styleHash(dfbwall::Style(base)), h);
  using Change = void (*)(dfbwall::Style&);
  const Change changes[] = {
      [](dfbwall::Style& s) { s.volumes.push_back(s.volumes[0]); },
      [](dfbwall::Style& s) { s.volumes[0].name = "other"; },
      [](dfbwall::Style& s) { s.volumes[0].grid.dims[2] += 1; },
      [](dfbwall::Style& s) { s.volumes[0].grid.origin[1] += 0.5f; },
      [](dfbwall::Style& s) { s.volumes[0].grid.spacing[0] *= 2; },
      [](dfbwall::Style& s) { s.volumes[0].transferFunction = "viridis"; },
      [](dfbwall::Style& s) { s.volumes[0].maxOpacity += 0.01f; },
      [](dfbwall::Style& s) { s.volumes[0].autoRange = !s.volumes[0].autoRange; },
      [](dfbwall::Style& s) { s.volumes[0].valueMin -= 1; },
      [](dfbwall::Style& s) { s.volumes[0].valueMax += 1; },
      [](dfbwall::Style& s) { s.volumes[0].visible = !s.volumes[0].visible; },
      [](dfbwall::Style& s) { s.isosurfaces.pop_back(); },
      [](dfbwall::Style& s) { s.isosurfaces[0].volume = 1; },
      [](dfbwall::Style& s) { s.isosurfaces[0].value += 1; },
      [](dfbwall::Style& s) { s.isosurfaces[0].color[2] = 0; },
      [](dfbwall::Style& s) { s.isosurfaces[0].opacity = 0.25f; },
      [](dfbwall::Style& s) { s.particleColor[0] = 0; },
      [](dfbwall::Style& s) { s.particleOpacity = 0.5f; },
      [](dfbwall::Style& s) { s.meshColor[1] = 0; },
      [](dfbwall::Style& s) { s.meshOpacity = 0.5f; },
      [](dfbwall::Style& s) { s.lights.clear(); },
      [](dfbwall::Style& s) { s.lights[0].kind = dfbwall::Light::Kind::Point; },
      [](dfbwall::Style& s) { s.lights[0].direction[0] = 1; },
      [](dfbwall::Style& s) { s.lights[0].position[2] = 3; },
      [](dfbwall::Style& s) { s.lights[0].color[1] = 0.5f; },
      [](dfbwall::Style& s) { s.lights[0].intensity = 2; },
      [](dfbwall::Style& s) { s.aoSamples += 1; },
      [](dfbwall::Style& s) { s.aoDistance *= 2; },
      [](dfbwall::Style& s) { s.shadows = !s.shadows; },
      [](dfbwall::Style& s) { s.samplingRate = 2; },
      [](dfbwall::Style& s) { s.background[2] = 1; },
      [](dfbwall::Style& s) { s.samplesPerPixel = 4; },
      [](dfbwall::Style& s) { s.seed += 1; },
  };
  std::vector<std::uint64_t> seen{h};
  for (std::size_t i = 0; i < std::size(changes); ++i) {
    dfbwall::Style changed = base;
    changes[i](changed);
    const std::uint64_t c = dfbwall::styleHash(changed);
    EXPECT_NE(c, h) << "change " << i;
    EXPECT_EQ(std::count(seen.begin(), seen.end(), c), 0) << "change " << i;
    seen.push_back(c);
  }
  // Strings are framed by their length: moving a character between two names is a change.
  dfbwall::Style a = base, b = base;
  a.volumes.push_back(a.volumes[0]);
  b.volumes.push_back(b.volumes[0]);
  a.volumes[0].name = "ab", a.volumes[1].name = "c";
  b.volumes[0].name = "a", b.volumes[1].name = "bc";
  EXPECT_NE(dfbwall::styleHash(a), dfbwall::styleHash(b));
  // Floats count by their bits: -0 is another style than +0.
  a = base, b = base;
  a.background[0] = 0.0f, b.background[0] = -0.0f;
  EXPECT_NE(dfbwall::styleHash(a), dfbwall::styleHash(b));
}

TEST(ApiEmbedding, DifferentStylesFailOnEveryRankAndCanBeFixed) {
  ASSERT_GE(testutil::worldSize(), 3) << "run with 3 ranks (tests/api/CMakeLists.txt)";
  dfbwall::SessionOptions o = options(2);
  o.timeoutSeconds = 20;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  dfbwall::Style st = style();
  if (testutil::worldRank() == 2) st.lights.push_back({});  // one light more, on rank 2 only
  session.setStyle(st);
  session.setCamera(camera());
  std::vector<float> storage;
  addBricks(session, storage);
  try {
    session.renderFrame();
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "the render ranks passed different styles to setStyle() (render rank 2 differs"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(session.framesRendered(), 0u);
  // Only a style change tells: a later frame with the same styles fails again.
  EXPECT_THROW(session.renderFrame(), std::runtime_error);
  // The ranks agreed on the failure, so the session is still in step: the same style everywhere
  // renders.
  session.setStyle(style());
  EXPECT_NO_THROW(session.renderFrame());
  EXPECT_EQ(session.framesRendered(), 1u);
  session.close();
}

TEST(ApiEmbedding, AStyleMissingOnOneRankFailsOnEveryRank) {
  dfbwall::SessionOptions o = options(2);
  o.timeoutSeconds = 20;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  if (testutil::worldRank() != 1) session.setStyle(style());
  session.setCamera(camera());
  try {
    session.renderFrame();
    ADD_FAILURE() << "no error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("renderFrame() before setStyle() on render rank 1"),
              std::string::npos)
        << e.what();
  }
  session.close();
}

// An object id nobody registers: a message for it is what a faulty peer (or a message of another
// version) would send, reported by the receiving rank's messenger.
constexpr std::uint64_t kNobody = 0x7E57;

std::string caught(dfbwall::Session& session) {
  try {
    session.renderFrame();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ApiEmbedding, AMessengerErrorIsThrownOnEveryRankInsteadOfAborting) {
  ASSERT_GE(testutil::worldSize(), 3) << "run with 3 ranks (tests/api/CMakeLists.txt)";
  const int rank = testutil::worldRank();
  dfbwall::SessionOptions o = options(2);
  o.timeoutSeconds = 20;
  dfbwall::TestedSession session(MPI_COMM_WORLD, o);
  session.setStyle(style());
  session.setCamera(camera());
  std::vector<float> storage;
  addBricks(session, storage);
  session.renderFrame();
  // Every rank is out of its frame: the message below arrives between calls (during one, that
  // call would throw it on rank 1 alone).
  MPI_Barrier(MPI_COMM_WORLD);
  // Rank 0 sends rank 1 a message for no object; once every rank has handled what was sent, rank
  // 1's messenger has reported it (before: MPI_Abort, the whole job gone).
  if (rank == 0) session.send(1, kNobody);
  session.quiesce();
  setFloatMode({false, false});
  // Every rank throws at the next frame, together: rank 1 the cause, the others who failed.
  const std::string first = caught(session);
  if (rank == 1) {
    EXPECT_NE(first.find("dfbwall: error on rank 1 ("), std::string::npos) << first;
    EXPECT_NE(first.find("message from rank 0 to object id " + std::to_string(kNobody) +
                         " on rank 1, which has no object registered under that id"),
              std::string::npos)
        << first;
  } else {
    EXPECT_NE(first.find("dfbwall: render rank 1 failed"), std::string::npos) << first;
  }
  EXPECT_FALSE(floatMode().flushZero);
  EXPECT_FALSE(floatMode().denormalsZero);
  // The session is unusable from now on, on every rank alike (so they stay in step)...
  const std::string second = caught(session);
  EXPECT_EQ(second.substr(0, 20), first.substr(0, 20)) << second;
  EXPECT_EQ(session.framesRendered(), 1u);
  // ...and still closes: the error was thrown already, close() does not throw it again.
  EXPECT_NO_THROW(session.close());
}

TEST(ApiEmbedding, AMessengerErrorAfterTheLastFrameIsThrownByClose) {
  ASSERT_GE(testutil::worldSize(), 3) << "run with 3 ranks (tests/api/CMakeLists.txt)";
  const int rank = testutil::worldRank();
  dfbwall::TestedSession session(MPI_COMM_WORLD, options(2));
  session.setStyle(style());
  session.setCamera(camera());
  std::vector<float> storage;
  addBricks(session, storage);
  session.renderFrame();
  MPI_Barrier(MPI_COMM_WORLD);  // every rank is out of its frame (as above)
  // Rank 0 sends rank 2 a message for no object; close() quiesces the messaging, so rank 2 has
  // handled it before close() returns, and close() throws it there only.
  if (rank == 0) session.send(2, kNobody);
  if (rank == 2) {
    try {
      session.close();
      ADD_FAILURE() << "no error";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("dfbwall: error on rank 2 ("), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("to object id " + std::to_string(kNobody)),
                std::string::npos)
          << e.what();
    }
  } else {
    EXPECT_NO_THROW(session.close());
  }
  // Closed all the same: its communicators are released, a second close() does nothing.
  EXPECT_NO_THROW(session.close());
}

}  // namespace
