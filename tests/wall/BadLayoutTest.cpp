// Every class of bad layout gives its own precise message: file, line, column, the display and
// the field, and what is wrong, then the line echoed. Problems are all reported, not just the
// first.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "wall/layout/Layout.h"

namespace {

std::string badFile(const std::string& name) {
  return std::string(DFBWALL_SOURCE_DIR) + "/tests/wall/bad/" + name;
}

// Reads tests/wall/bad/NAME and requires exactly `expected` problems, in order; each expected
// text is the message after "PATH:", and each problem echoes its line below it.
void expectProblems(const std::string& name, const std::vector<std::string>& expected) {
  SCOPED_TRACE(name);
  const wall::LayoutResult r = wall::readLayoutFile(badFile(name));
  EXPECT_FALSE(r.ok());
  ASSERT_EQ(r.problems.size(), expected.size()) << wall::joinProblems(r.problems);
  for (size_t i = 0; i < expected.size(); ++i) {
    const std::string want = badFile(name) + ":" + expected[i];
    // Compare the start: the tail (hints, lists of known fields) may grow.
    EXPECT_EQ(r.problems[i].substr(0, want.size()), want) << "problem " << i;
    const std::string line = expected[i].substr(0, expected[i].find(':'));
    EXPECT_NE(r.problems[i].find("\n" + std::string(5 - std::min<size_t>(line.size(), 4), ' ') +
                                 line + " | "),
              std::string::npos)
        << "no echo of line " << line << ": " << r.problems[i];
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
                 {"9:10: display 'b'.origin: overlaps display 'a' (line 2) in the 20x30 "
                  "pixels [80, 50] to [100, 80)"});
}

TEST(BadLayout, ZeroAndNegativeSizes) {
  expectProblems("zero-size.toml", {"10:8: display 'r0c1'.size: width must be positive, got 0",
                                    "15:8: display 'r0c2'.size: height must be positive, got -5"});
}

TEST(BadLayout, DuplicateName) {
  expectProblems("duplicate-name.toml",
                 {"8:8: display 'left'.name: duplicate name 'left'; the display at line 2 "
                  "has it already"});
}

TEST(BadLayout, NameWithASpace) {
  expectProblems("bad-name.toml", {"3:8: display 'left wall'.name: 'left wall' may contain only "
                                   "letters, digits, '-' and '_'"});
}

TEST(BadLayout, ProcessIndicesWithAGap) {
  expectProblems("process-gap.toml",
                 {"12:11: display 'b'.process: process indices must run from 0 without "
                  "gaps, but no display has process 1"});
}

TEST(BadLayout, SomeDisplaysWithoutProcess) {
  expectProblems("missing-process.toml",
                 {"8:1: display 'b'.process: missing; display 'a' (line 6) sets "
                  "'process', so every display must"});
}

TEST(BadLayout, UnknownKeysAreNotIgnored) {
  expectProblems("unknown-key.toml",
                 {"4:1: display 'a': unknown field 'orign' (did you mean 'origin'?); known fields: "
                  "name, origin, size, process, host, monitor, fullscreen",
                  "2:1: display 'a'.origin: missing",
                  "11:1: display 'b': unknown field 'fulscreen' (did you mean 'fullscreen'?)"});
}

TEST(BadLayout, WrongTypes) {
  expectProblems("wrong-type.toml",
                 {"5:8: display 'a'.size: expected [w, h] (2 integers), got a string",
                  "9:11: display 'b'.origin: expected an integer, got a floating-point number",
                  "10:8: display 'b'.size: expected [w, h] (2 integers), got 3 elements",
                  "11:11: display 'b'.process: expected an integer, got a string",
                  "2:1: display 'a'.process: missing; display 'b' (line 11) sets"});
}

TEST(BadLayout, GridWithNegativeBezelAndNoColumns) {
  expectProblems("grid-bezels.toml", {"3:11: grid.columns: must be positive, got 0",
                                      "6:12: grid.bezel_px: right bezel must be 0 or more"});
}

TEST(BadLayout, GridMillimetresWithoutPitch) {
  expectProblems("grid-mm-no-pitch.toml",
                 {"6:12: grid.pixel_pitch_mm: missing; bezel_mm needs the pixel pitch"});
}

TEST(BadLayout, NoDisplays) {
  expectProblems("no-displays.toml", {"1:1: no displays: describe them with [[display]] tables"});
}

TEST(BadLayout, MisspelledGridTable) {
  expectProblems("unknown-table.toml",
                 {"2:2: unknown table or key 'gird' (did you mean 'grid'?); the file's tables and "
                  "keys: display, grid, description",
                  "1:1: no displays"});
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
  EXPECT_EQ(r.problems[0].rfind("inline.toml:13:1: display 'c': unknown field 'colour'", 0), 0u);
  EXPECT_EQ(r.problems[1].rfind("inline.toml:7:10: display 'b'.origin: overlaps", 0), 0u);
}

TEST(BadLayout, ValidateLayoutOnACodeBuiltLayout) {
  wall::Layout l;
  l.file = "code";
  l.displays.push_back({"x", {0, 0, 10, 10}, 0, "", 0, false, {}, wall::Eye::Centre, {}, {}});
  l.displays.push_back({"x", {5, 5, 15, 15}, 3, "", 0, false, {}, wall::Eye::Centre, {}, {}});
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
                 {"3:11: grid.columns: 3000 x 3000 panels: at most 1024 displays"});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
}

TEST(BadLayout, HugeProcessIndexIsOneMessage) {
  expectProblems("huge-process.toml", {"6:11: display 'a'.process: must be from 0 to 1023"});
}

TEST(BadLayout, OriginsNearTheIntLimitsAreRefused) {
  expectProblems("far-origins.toml", {"9:10: display 'right'.origin: the canvas, "
                                      "4294966100x4294966100 pixels, is too large"});
}

TEST(BadLayout, InfinitePixelPitchIsRefused) {
  expectProblems("pitch-inf.toml",
                 {"7:18: grid.pixel_pitch_mm: expected a finite number, got inf"});
}

}  // namespace
