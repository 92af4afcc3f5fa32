#pragma once
// The layouts shipped in configs/walls/, as the wall tests read them.
#include <gtest/gtest.h>

#include <string>

#include "wall/layout/Layout.h"

namespace test {

inline std::string shippedLayoutPath(const std::string& name) {
  return std::string(DFBWALL_SOURCE_DIR) + "/configs/walls/" + name;
}

// The shipped layout `name`; a problem in it fails the calling test.
inline wall::Layout loadShippedLayout(const std::string& name) {
  wall::LayoutResult r = wall::readLayoutFile(shippedLayoutPath(name));
  EXPECT_TRUE(r.ok()) << wall::joinProblems(r.problems);
  return r.layout;
}

}  // namespace test
