// The diagnostics of a TOML input on their own: where a problem is, the echoed line and its
// caret, the suggested key, typed readers, syntax errors, and one error listing every problem.
#include "base/TomlDiagnostics.h"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <string_view>

namespace {

using base::TomlDiagnostics;

constexpr std::array<std::string_view, 4> kKnown = {"origin", "size", "fullscreen", "grid"};

TEST(TomlDiagnostics, SuggestsTheClosestKeyOnlyForALikelyTypo) {
  EXPECT_EQ(base::closestKey("orign", kKnown), "origin");
  EXPECT_EQ(base::closestKey("fulscreen", kKnown), "fullscreen");
  EXPECT_EQ(base::closestKey("gird", kKnown), "grid");  // neighbours swapped: one edit
  EXPECT_EQ(base::closestKey("SIZE", kKnown), "size");  // case is no typo
  EXPECT_EQ(base::closestKey("dims", std::array<std::string_view, 1>{"time"}), std::nullopt);
  EXPECT_EQ(base::closestKey("up", std::array<std::string_view, 1>{"fo"}), std::nullopt);
  EXPECT_EQ(base::closestKey("colour", kKnown), std::nullopt);
  EXPECT_EQ(base::closestKey(std::string(1000, 'x'), kKnown), std::nullopt);
}

TEST(TomlDiagnostics, EchoesTheLineWithACaretUnderTheColumn) {
  const std::string text = "[camera]\nfov = \"wide\"\n";
  EXPECT_EQ(base::sourceExcerpt(text, 2, 7, 6),
            "    2 | fov = \"wide\"\n"
            "      |       ^~~~~~");
  EXPECT_EQ(base::sourceExcerpt(text, 1, 1), "    1 | [camera]\n      | ^");
  EXPECT_EQ(base::sourceExcerpt(text, 9, 1), "") << "no such line";
  EXPECT_EQ(base::sourceExcerpt(text, 0, 0), "");
  // A wide gutter for a long file; still indented, so the echo never starts a line.
  const std::string tall = std::string(123456, '\n') + "x = 1\n";
  EXPECT_EQ(base::sourceExcerpt(tall, 123457, 5), " 123457 | x = 1\n        |     ^");
}

TEST(TomlDiagnostics, CaretsFollowTabsAndCountCodePoints) {
  // TOML++ counts columns in code points: "é" is one, though two bytes.
  EXPECT_EQ(base::sourceExcerpt("\tname = \"é\" x\n", 1, 13),
            "    1 | \tname = \"é\" x\n      | \t           ^");
  // Control characters would garble a terminal.
  EXPECT_EQ(base::sourceExcerpt("a = \"\x1b[2J\"\n", 1, 1), "    1 | a = \"?[2J\"\n      | ^");
}

TEST(TomlDiagnostics, CutsALongLineToAWindowAroundTheColumn) {
  const std::string line = std::string(5000, 'a') + "X" + std::string(5000, 'b');
  const std::string e = base::sourceExcerpt(line, 1, 5001);
  EXPECT_LT(e.size(), 300u) << e;
  const std::string echoed = e.substr(0, e.find('\n'));
  const std::string caret = e.substr(e.find('\n') + 1);
  EXPECT_EQ(echoed.substr(echoed.find(" | ") + 3, 3), "...");
  EXPECT_EQ(echoed.substr(echoed.size() - 3), "...");
  EXPECT_EQ(echoed[caret.find('^')], 'X') << e;
}

TEST(TomlDiagnostics, ASyntaxErrorHasItsLineAndColumnAndEchoesTheLine) {
  TomlDiagnostics d("wall.toml", "[[display]]\nname = \"a\"\norigin = [0, 0\nsize = [1, 1]\n");
  EXPECT_FALSE(d.parse());
  ASSERT_EQ(d.problems().size(), 1u);
  const base::Diagnostic& p = d.problems()[0];
  EXPECT_EQ(p.where.file, "wall.toml");
  EXPECT_EQ(p.where.line, 4);
  EXPECT_GT(p.where.column, 0);
  EXPECT_EQ(p.message.rfind("TOML syntax error: ", 0), 0u) << p.message;
  EXPECT_EQ(
      p.text().rfind("wall.toml:4:" + std::to_string(p.where.column) + ": TOML syntax error", 0),
      0u)
      << p.text();
  EXPECT_NE(p.text().find("\n    4 | size = [1, 1]\n      | "), std::string::npos) << p.text();
}

TEST(TomlDiagnostics, UnknownKeysNameTheirPlaceAndTheClosestKnownOne) {
  TomlDiagnostics d("x.toml", "[display]\norign = 1\nzzz = 2\n");
  const auto root = d.parse();
  ASSERT_TRUE(root);
  d.unknownKeys(*(*root)["display"].as_table(), "display 'a'", kKnown);
  d.unknownKeys(*root, "", std::array<std::string_view, 1>{"dispaly"});
  ASSERT_EQ(d.texts().size(), 3u);
  EXPECT_EQ(d.texts()[0],
            "x.toml:2:1: display 'a': unknown field 'orign' (did you mean 'origin'?); known "
            "fields: origin, size, fullscreen, grid\n"
            "    2 | orign = 1\n"
            "      | ^~~~~");
  EXPECT_EQ(d.texts()[1].rfind("x.toml:3:1: display 'a': unknown field 'zzz'; known fields: ", 0),
            0u)
      << d.texts()[1];
  EXPECT_EQ(d.texts()[2].rfind("x.toml:1:2: unknown table or key 'display' (did you mean "
                               "'dispaly'?); the file's tables and keys: dispaly",
                               0),
            0u)
      << d.texts()[2];
}

TEST(TomlDiagnostics, TypedReadersNameTheExpectedTypeAndTheOneFound) {
  TomlDiagnostics d("t.toml",
                    "i = 1.5\nn = \"x\"\nf = inf\nb = 1\ns = 2\nv = [1, \"y\", 3]\nw = [1, 2]\n"
                    "t = 3\nok = 7\n");
  const auto root = d.parse();
  ASSERT_TRUE(root);
  const toml::table& t = *root;
  EXPECT_FALSE(d.integer(*t.get("i"), "i"));
  EXPECT_FALSE(d.number(*t.get("n"), "n"));
  EXPECT_FALSE(d.number(*t.get("f"), "f"));
  EXPECT_FALSE(d.boolean(*t.get("b"), "b"));
  EXPECT_FALSE(d.string(*t.get("s"), "s"));
  EXPECT_FALSE(d.numbers(*t.get("v"), "v", 3, "[x, y, z]"));
  EXPECT_FALSE(d.integers(*t.get("w"), "w", 3, "[x, y, z]"));
  EXPECT_FALSE(d.table(*t.get("t"), "t"));
  EXPECT_EQ(d.integer(*t.get("ok"), "ok"), 7);
  EXPECT_EQ(d.number(*t.get("ok"), "ok"), 7.0);
  const std::vector<std::string> texts = d.texts();
  const char* expected[] = {
      "t.toml:1:5: i: expected an integer, got a floating-point number",
      "t.toml:2:5: n: expected a number, got a string",
      "t.toml:3:5: f: expected a finite number, got inf",
      "t.toml:4:5: b: expected true or false, got an integer",
      "t.toml:5:5: s: expected a string, got an integer",
      "t.toml:6:9: v: expected a number, got a string",  // at the element
      "t.toml:7:5: w: expected [x, y, z] (3 integers), got 2 elements",
      "t.toml:8:5: t: expected a table, got an integer",
  };
  ASSERT_EQ(texts.size(), std::size(expected));
  for (std::size_t i = 0; i < texts.size(); ++i)
    EXPECT_EQ(texts[i].substr(0, texts[i].find('\n')), expected[i]);
}

TEST(TomlDiagnostics, OneErrorListsEveryProblemAndIsLocatedAtTheFirst) {
  TomlDiagnostics d("s.toml", "a = 1\nb = 2\n");
  EXPECT_NO_THROW(d.throwIfAny());
  d.add(2, 5, "b", "must be odd");
  d.add(1, 1, "a", "must be even");
  d.add(0, 0, "", "the file as a whole");
  try {
    d.throwIfAny();
    FAIL() << "no error";
  } catch (const base::Error& e) {
    EXPECT_EQ(e.where().file, "s.toml");
    EXPECT_EQ(e.where().line, 2);
    EXPECT_EQ(e.where().column, 5);
    EXPECT_STREQ(e.what(),
                 "s.toml:2:5: b: must be odd\n"
                 "    2 | b = 2\n"
                 "      |     ^\n"
                 "s.toml:1:1: a: must be even\n"
                 "    1 | a = 1\n"
                 "      | ^\n"
                 "s.toml: the file as a whole");
  }
}

TEST(TomlDiagnostics, ManyProblemsAreCountedPastTheOnesKept) {
  TomlDiagnostics d("many.toml");
  for (int i = 0; i < 1000; ++i) d.add(i + 1, 1, "k", "bad");
  EXPECT_EQ(d.count(), 1000u);
  EXPECT_EQ(d.problems().size(), TomlDiagnostics::kMaxKept);
  EXPECT_EQ(d.texts().back(), "many.toml: and 900 more problems");
}

TEST(TomlDiagnostics, AFileThatCannotBeReadIsOneProblem) {
  TomlDiagnostics d("/nonexistent/wall.toml");
  EXPECT_FALSE(d.readFile("layout file"));
  ASSERT_EQ(d.texts().size(), 1u);
  EXPECT_EQ(d.texts()[0],
            "/nonexistent/wall.toml: cannot read the layout file (No such file or directory)");
}

}  // namespace
