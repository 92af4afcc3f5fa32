// Every class of bad layout gives its own precise message: file, line, the display and the
// field, and what is wrong. Problems are all reported, not just the first.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "wall/layout/Layout.h"

namespace {

std::string badFile(const std::string& name) {
  return std::string(DFBWALL_SOURCE_DIR) + "/tests/wall/bad/" + name;
}

// Reads tests/wall/bad/NAME and requires exactly `expected` problems, in order; each expected
// text is the message after "PATH:".
void expectProblems(const std::string& name, const std::vector<std::string>& expected) {
  SCOPED_TRACE(name);
  const wall::LayoutResult r = wall::readLayoutFile(badFile(name));
  EXPECT_FALSE(r.ok());
  ASSERT_EQ(r.problems.size(), expected.size()) << wall::joinProblems(r.problems);
  for (size_t i = 0; i < expected.size(); ++i) {
    const std::string want = badFile(name) + ":" + expected[i];
    // Compare the start: the tail (hints, lists of known fields) may grow.
    EXPECT_EQ(r.problems[i].substr(0, want.size()), want) << "problem " << i;
  }
}

TEST(BadLayout, SyntaxErrorHasLineAndColumn) {
  const wall::LayoutResult r = wall::readLayoutFile(badFile("syntax.toml"));
  ASSERT_EQ(r.problems.size(), 1u) << wall::joinProblems(r.problems);
  // The unclosed array on line 4 runs into 'size' on line 5.
  EXPECT_EQ(r.problems[0].rfind(badFile("syntax.toml") + ":5:", 0), 0u) << r.problems[0];
  EXPECT_NE(r.problems[0].find("TOML syntax error"), std::string::npos) << r.problems[0];
  const std::string afterLine = r.problems[0].substr(badFile("syntax.toml").size() + 3);
  EXPECT_TRUE(afterLine[0] >= '1' && afterLine[0] <= '9') << "no column: " << r.problems[0];
}

TEST(BadLayout, Overlap) {
  expectProblems("overlap.toml",
                 {"9: display 'b': field 'origin': overlaps display 'a' (line 2) in the 20x30 "
                  "pixels [80, 50] to [100, 80)"});
}

TEST(BadLayout, ZeroAndNegativeSizes) {
  expectProblems("zero-size.toml",
                 {"10: display 'r0c1': field 'size': width must be positive, got 0",
                  "15: display 'r0c2': field 'size': height must be positive, "
                  "got -5"});
}

TEST(BadLayout, DuplicateName) {
  expectProblems("duplicate-name.toml",
                 {"8: display 'left': field 'name': duplicate name 'left'; the display at line 2 "
                  "has it already"});
}

TEST(BadLayout, NameWithASpace) {
  expectProblems("bad-name.toml", {"3: display 'left wall': field 'name': 'left wall' may contain "
                                   "only letters, digits, '-' and '_'"});
}

TEST(BadLayout, ProcessIndicesWithAGap) {
  expectProblems("process-gap.toml",
                 {"12: display 'b': field 'process': process indices must run from 0 without "
                  "gaps, but no display has process 1"});
}

TEST(BadLayout, SomeDisplaysWithoutProcess) {
  expectProblems("missing-process.toml",
                 {"8: display 'b': field 'process': missing; display 'a' (line 6) sets "
                  "'process', so every display must"});
}

TEST(BadLayout, UnknownKeysAreNotIgnored) {
  expectProblems("unknown-key.toml",
                 {"4: display 'a': unknown field 'orign' (did you mean 'origin'?)",
                  "2: display 'a': field 'origin': missing",
                  "11: display 'b': unknown field 'fulscreen' (did you mean 'fullscreen'?)"});
}

TEST(BadLayout, WrongTypes) {
  expectProblems("wrong-type.toml",
                 {"5: display 'a': field 'size': expected [w, h] (2 integers), got a string",
                  "9: display 'b': field 'origin': expected an integer, got a floating-point "
                  "number",
                  "10: display 'b': field 'size': expected [w, h] (2 integers), got 3 elements",
                  "11: display 'b': field 'process': expected an integer, got a string",
                  "2: display 'a': field 'process': missing; display 'b' (line 11) sets"});
}

TEST(BadLayout, GridWithNegativeBezelAndNoColumns) {
  expectProblems("grid-bezels.toml", {"3: grid: field 'columns': must be positive, got 0",
                                      "6: grid: field 'bezel_px': right bezel must be 0 or more"});
}

TEST(BadLayout, GridMillimetresWithoutPitch) {
  expectProblems("grid-mm-no-pitch.toml",
                 {"6: grid: field 'pixel_pitch_mm': missing; bezel_mm needs the pixel pitch"});
}

TEST(BadLayout, NoDisplays) {
  expectProblems("no-displays.toml", {"1: no displays: describe them with [[display]] tables"});
}

TEST(BadLayout, MisspelledGridTable) {
  expectProblems("unknown-table.toml",
                 {"2: unknown table or key 'gird' (did you mean 'grid'?)", "1: no displays"});
}

TEST(BadLayout, SemanticProblemsSurviveATypoElsewhere) {
  // A typo in one display must not hide an overlap between two others.
  const wall::LayoutResult r = wall::readLayoutText(R"([[display]]
name = "a"
origin = [0, 0]
size = [100, 80]
[[display]]
name = "b"
origin = [50, 0]
size = [100, 80]
[[display]]
name = "c"
origin = [500, 0]
size = [100, 80]
colour = "red"
)",
                                                    "inline.toml");
  ASSERT_EQ(r.problems.size(), 2u) << wall::joinProblems(r.problems);
  EXPECT_EQ(r.problems[0].rfind("inline.toml:13: display 'c': unknown field 'colour'", 0), 0u);
  EXPECT_EQ(r.problems[1].rfind("inline.toml:7: display 'b': field 'origin': overlaps", 0), 0u);
}

TEST(BadLayout, ValidateLayoutOnACodeBuiltLayout) {
  wall::Layout l;
  l.file = "code";
  l.displays.push_back({"x", {0, 0, 10, 10}, 0, "", 0, false, {}});
  l.displays.push_back({"x", {5, 5, 15, 15}, 3, "", 0, false, {}});
  const wall::Problems p = wall::validateLayout(l);
  // Duplicate name, overlap, and processes 1 and 2 missing (one message per gap).
  ASSERT_EQ(p.size(), 3u) << wall::joinProblems(p);
  EXPECT_NE(p[0].find("duplicate name 'x'"), std::string::npos);
  EXPECT_NE(p[1].find("overlaps"), std::string::npos);
  EXPECT_NE(p[2].find("no display has process 1 to 2"), std::string::npos);
}

// Hostile layouts that used to hang, exhaust memory or crash every rank: each is one message,
// at once.
TEST(BadLayout, HugeGridIsRefusedBeforeExpanding) {
  const auto start = std::chrono::steady_clock::now();
  expectProblems("huge-grid.toml",
                 {"2: grid: field 'columns': 3000 x 3000 panels: at most 1024 displays"});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
}

TEST(BadLayout, HugeProcessIndexIsOneMessage) {
  expectProblems("huge-process.toml", {"6: display 'a': field 'process': must be from 0 to 1023"});
}

TEST(BadLayout, OriginsNearTheIntLimitsAreRefused) {
  expectProblems("far-origins.toml", {"1: the canvas, 4294966100x4294966100 pixels, is too large"});
}

TEST(BadLayout, InfinitePixelPitchIsRefused) {
  expectProblems("pitch-inf.toml",
                 {"7: grid: field 'pixel_pitch_mm': expected a finite number, got inf"});
}

}  // namespace
