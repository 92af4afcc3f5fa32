// Embedding without traps: bad input on one rank fails the next frame on every rank with an
// InputError the ranks recover from, MPI_COMM_NULL is refused, and a rank whose session is
// destroyed without close() makes the others fail at once, naming it, instead of at their
// deadline (the destructor runs no collective).
#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "api/DataDistributed.h"
#include "tests/MpiTestUtil.h"
#include "tests/api/ApiTestScene.h"

namespace {

using namespace apitest;

dfbwall::SessionOptions options() {
  dfbwall::SessionOptions o;
  o.width = 64, o.height = 48, o.tileSize = 16, o.threads = 2, o.timeoutSeconds = 60;
  return o;
}

void addSlabs(dfbwall::Session& session, std::vector<float>& storage) {
  for (int b = testutil::worldRank(); b < 3; b += testutil::worldSize())
    session.addBrick(brick(b, 3, storage));
}

TEST(ApiLeaving, ARefusedBrickFailsTheNextFrameOnEveryRankAndCanBeFixed) {
  ASSERT_GE(testutil::worldSize(), 3) << "run with 3 ranks (tests/api/CMakeLists.txt)";
  dfbwall::Session session(MPI_COMM_WORLD, options());
  session.setStyle(style());
  session.setCamera(camera());
  std::vector<float> storage;
  addSlabs(session, storage);
  if (testutil::worldRank() == 1) {
    // A voxel box that reaches past the field: refused here, but not thrown on this rank alone.
    dfbwall::Brick bad = brick(1, 3, storage);
    bad.id = 7;
    bad.volumes[0].hi[2] = kN + 4;
    EXPECT_NO_THROW(session.addBrick(bad));
  }
  try {
    session.renderFrame();
    ADD_FAILURE() << "no error";
  } catch (const dfbwall::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("render rank 1 refused its input: brick 7"), std::string::npos) << what;
  }
  EXPECT_EQ(session.framesRendered(), 0u);
  // Every rank dropped what it gave for this frame: corrected input renders, on every rank.
  addSlabs(session, storage);
  EXPECT_NO_THROW(session.renderFrame());
  EXPECT_EQ(session.framesRendered(), 1u);
  session.close();
}

TEST(ApiLeaving, MpiCommNullIsRefused) {
  try {
    dfbwall::Session session(MPI_COMM_NULL, options());
    ADD_FAILURE() << "no error";
  } catch (const dfbwall::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("MPI_COMM_NULL"), std::string::npos) << e.what();
  }
}

TEST(ApiLeaving, ARankThatLeavesWithoutCloseFailsTheOthersAtOnce) {
  ASSERT_GE(testutil::worldSize(), 3) << "run with 3 ranks (tests/api/CMakeLists.txt)";
  const int rank = testutil::worldRank();
  std::vector<float> storage;
  std::optional<dfbwall::Session> session;
  session.emplace(MPI_COMM_WORLD, options());
  session->setStyle(style());
  session->setCamera(camera());
  addSlabs(*session, storage);
  session->renderFrame();
  if (rank == 2) {
    // Returns early: the destructor leaves without waiting for anyone.
    const auto start = std::chrono::steady_clock::now();
    session.reset();
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
    return;
  }
  // The others' next frame fails within moments, not at their 60 s deadline, naming rank 2.
  const auto start = std::chrono::steady_clock::now();
  std::string what = "no error";
  try {
    for (int i = 0; i < 3; ++i) session->renderFrame();
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10)) << what;
  EXPECT_NE(what.find("rank 2 ("), std::string::npos) << what;
  EXPECT_NE(what.find("left without closing"), std::string::npos) << what;
  // close() cannot finish either: it says so at once too.
  try {
    session->close();
    ADD_FAILURE() << "close() on a session a rank left";
  } catch (const std::runtime_error& e) {
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(15)) << e.what();
  }
  session.reset();  // leaves in turn: no hang
}

}  // namespace
