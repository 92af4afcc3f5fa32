#include "base/Error.h"

#include <gtest/gtest.h>

#include "base/ObjectIds.h"

namespace {

TEST(Error, PrintsAsMuchOfItsPlaceAsIsKnown) {
  EXPECT_STREQ(base::Error({"wall.toml", 12, 7}, "unknown key 'bezle'").what(),
               "wall.toml:12:7: unknown key 'bezle'");
  EXPECT_STREQ(base::Error({"wall.toml", 12, 0}, "bad").what(), "wall.toml:12: bad");
  EXPECT_STREQ(base::Error({"wall.toml", 0, 0}, "bad").what(), "wall.toml: bad");
  EXPECT_STREQ(base::Error("no file").what(), "no file");
}

TEST(Error, KeepsItsPlaceAndMessageApart) {
  const base::Error e({"scene.toml", 3, 14}, "spp must be a positive integer");
  EXPECT_EQ(e.where().file, "scene.toml");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_EQ(e.where().column, 14);
  EXPECT_EQ(e.message(), "spp must be a positive integer");
  EXPECT_FALSE(base::Error("x").where().known());
}

TEST(Error, DeadlinesAreErrors) {
  try {
    throw base::DeadlineError("frame 3: another rank did not join within 100 ms");
  } catch (const base::Error& e) {
    EXPECT_STREQ(e.what(), "frame 3: another rank did not join within 100 ms");
  }
}

TEST(ObjectIds, FollowOneAnother) {
  using base::MessageObject;
  EXPECT_EQ(base::objectId(MessageObject::kRunControl),
            base::objectId(MessageObject::kFrameBuffer) + 1);
  EXPECT_NE(base::objectId(MessageObject::kSteering), base::objectId(MessageObject::kWallControl));
}

}  // namespace
