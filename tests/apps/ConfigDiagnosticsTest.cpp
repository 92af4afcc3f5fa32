// Layouts, scenes, camera paths and volume headers report problems in one form
// (base/TomlDiagnostics.h): each names the file, line and column and the field, echoes the line
// with a caret under the column, and a typo'd key is answered with the key it likely meant, the
// same words in a layout as in a scene. Every problem of a file is reported, not just the first.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "apps/CameraPath.h"
#include "base/Error.h"
#include "renderers/SceneToml.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"
#include "wall/layout/Layout.h"

namespace {

namespace fs = std::filesystem;

std::string writeFile(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(::testing::TempDir()) / "dfbwall-config-diagnostics";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// One problem as printed: its headline and the two lines echoing the file.
struct Printed {
  std::string file, rest;  // rest: "FIELD: MESSAGE" after the location
  int line = 0, column = 0;
};

// Splits `message` (all problems of `path`, whose text is `text`) into its problems and checks
// each: it starts "PATH:LINE:COLUMN: ", and the two lines below it echo line LINE of the file
// with a caret under column COLUMN.
std::vector<Printed> expectWellFormed(const std::string& message, const std::string& path,
                                      const std::string& text) {
  const std::vector<std::string> source = linesOf(text);
  const std::vector<std::string> lines = linesOf(message);
  const std::regex headline(R"(^(.*?):(\d+):(\d+): (.*)$)");
  const std::regex echo(R"(^ +(\d+) \| (.*)$)");
  std::vector<Printed> out;
  for (std::size_t i = 0; i < lines.size(); i += 3) {
    std::smatch m;
    if (!std::regex_match(lines[i], m, headline)) {
      ADD_FAILURE() << "no FILE:LINE:COLUMN in: " << lines[i] << "\nof:\n" << message;
      return out;
    }
    Printed p{m[1], m[4], std::stoi(m[2]), std::stoi(m[3])};
    EXPECT_EQ(p.file, path) << lines[i];
    out.push_back(p);
    if (i + 2 >= lines.size() || !std::regex_match(lines[i + 1], m, echo) ||
        static_cast<std::size_t>(p.line) > source.size() || p.line < 1) {
      ADD_FAILURE() << "no echo of line " << p.line << " below: " << lines[i] << "\nof:\n"
                    << message;
      return out;
    }
    EXPECT_EQ(std::stoi(m[1]), p.line) << lines[i + 1];
    EXPECT_EQ(m[2].str(), source[static_cast<std::size_t>(p.line) - 1]) << lines[i + 1];
    // The caret sits under the column (the files here are ASCII without tabs).
    const std::size_t bar = lines[i + 1].find(" | ") + 3;
    EXPECT_EQ(lines[i + 2].find('^'), bar + static_cast<std::size_t>(p.column) - 1)
        << lines[i + 1] << "\n"
        << lines[i + 2];
  }
  return out;
}

std::string errorOf(const std::function<void()>& load) {
  try {
    load();
  } catch (const base::Error& e) {
    return e.what();
  }
  return "(no error)";
}

// What a typo'd key reads like after its subject: the same in every kind of file.
const std::string kTypo = "unknown field 'orign' (did you mean 'origin'?); known fields: ";

TEST(ConfigDiagnostics, ALayoutReportsItsTypoAndWrongTypeWithPlaceAndEcho) {
  const std::string text =
      "[[display]]\n"
      "name = \"left\"\n"
      "orign = [0, 0]\n"
      "size = [100, \"80\"]\n";
  const std::string path = writeFile("layout.toml", text);
  const std::string e = errorOf([&] { wall::loadLayout(path); });
  const std::vector<Printed> p = expectWellFormed(e, path, text);
  ASSERT_EQ(p.size(), 3u) << e;
  EXPECT_EQ(p[0].line, 3);
  EXPECT_EQ(p[0].column, 1);
  EXPECT_EQ(p[0].rest.rfind("display 'left': " + kTypo, 0), 0u) << p[0].rest;
  EXPECT_EQ(p[1].line, 1);  // the display's table: 'origin' is missing
  EXPECT_EQ(p[1].rest.rfind("display 'left'.origin: missing", 0), 0u) << p[1].rest;
  EXPECT_EQ(p[2].line, 4);
  EXPECT_EQ(p[2].column, 14);
  EXPECT_EQ(p[2].rest, "display 'left'.size: expected an integer, got a string");
}

TEST(ConfigDiagnostics, ASceneReportsEveryProblemWithPlaceAndEchoAsALayoutDoes) {
  const std::string text =
      "[camera]\n"
      "position = [0, 0, -5]\n"
      "look_at = [0, 0, 0]\n"
      "fov = \"wide\"\n"
      "\n"
      "[[volumes]]\n"
      "name = \"w\"\n"
      "source = \"wavelet\"\n"
      "orign = [0, 0, 0]\n"
      "sigma = true\n";
  const std::string path = writeFile("scene.toml", text);
  const std::string e = errorOf([&] { renderers::readSceneToml(path); });
  const std::vector<Printed> p = expectWellFormed(e, path, text);
  // The wrong type in the camera does not stop the check of the volume, nor does one wrong
  // field stop the check of the others.
  ASSERT_EQ(p.size(), 3u) << e;
  EXPECT_EQ(p[0].line, 4);
  EXPECT_EQ(p[0].column, 7);
  EXPECT_EQ(p[0].rest, "camera.fov: expected a number, got a string");
  EXPECT_EQ(p[1].line, 9);
  EXPECT_EQ(p[1].column, 1);
  EXPECT_EQ(p[1].rest.rfind("volume 'w': " + kTypo, 0), 0u) << p[1].rest;
  EXPECT_EQ(p[2].line, 10);
  EXPECT_EQ(p[2].column, 9);
  EXPECT_EQ(p[2].rest, "volume 'w'.sigma: expected a number, got a boolean");
}

TEST(ConfigDiagnostics, ACameraPathReportsItsTypoAndWrongTypeWithPlaceAndEcho) {
  const std::string text =
      "fps = \"fast\"\n"
      "[[keyframe]]\n"
      "time = 0\n"
      "position = [0, 0, -5]\n"
      "lookat = [0, 0, 0]\n";
  const std::string path = writeFile("path.toml", text);
  const std::string e = errorOf([&] { app::CameraPath::load(path, {}); });
  const std::vector<Printed> p = expectWellFormed(e, path, text);
  ASSERT_EQ(p.size(), 3u) << e;
  EXPECT_EQ(p[0].line, 1);
  EXPECT_EQ(p[0].column, 7);
  EXPECT_EQ(p[0].rest, "fps: expected a number, got a string");
  EXPECT_EQ(p[1].line, 5);
  EXPECT_EQ(p[1].rest.rfind(
                "keyframe #1: unknown field 'lookat' (did you mean 'look_at'?); known fields: ", 0),
            0u)
      << p[1].rest;
  EXPECT_EQ(p[2].line, 2);
  EXPECT_EQ(p[2].rest, "keyframe #1.look_at: missing");
}

TEST(ConfigDiagnostics, ACameraPathWithoutKeyframesIsRefused) {
  for (const std::string text : {"fps = 10\n", "fps = 10\nkeyframe = []\n"}) {
    const std::string path = writeFile("no-keys.toml", text);
    const std::string e = errorOf([&] { app::CameraPath::load(path, {}); });
    const std::vector<Printed> p = expectWellFormed(e, path, text);
    ASSERT_EQ(p.size(), 1u) << e;
    EXPECT_EQ(p[0].rest, "keyframe: a camera path needs at least one [[keyframe]]");
  }
}

TEST(ConfigDiagnostics, SyntaxErrorsHaveLineAndColumnAndEchoInEveryKindOfFile) {
  struct Case {
    std::string name, text;
    std::function<void(const std::string&)> load;
    int line;
  };
  const Case cases[] = {
      {"layout-syntax.toml", "[[display]]\nname = \"a\nsize = [1, 1]\n",
       [](const std::string& p) { wall::loadLayout(p); }, 2},
      {"scene-syntax.toml", "[camera]\nposition = [0, 0, -5\nlook_at = [0, 0, 0]\n",
       [](const std::string& p) { renderers::readSceneToml(p); }, 3},
      {"path-syntax.toml", "fps = 30\n[[keyframe]\ntime = 0\n",
       [](const std::string& p) { app::CameraPath::load(p, {}); }, 2},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = writeFile(c.name, c.text);
    const std::string e = errorOf([&] { c.load(path); });
    const std::vector<Printed> p = expectWellFormed(e, path, c.text);
    ASSERT_EQ(p.size(), 1u) << e;
    EXPECT_EQ(p[0].line, c.line) << e;
    EXPECT_GT(p[0].column, 0) << e;
    EXPECT_EQ(p[0].rest.rfind("TOML syntax error: ", 0), 0u) << e;
  }
}

TEST(ConfigDiagnostics, VolumeHeadersNameTheirLineAndColumn) {
  // A header's own place, as base::SourceLocation...
  try {
    renderers::scivis::parseNrrdHeader("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 x 4\n\n",
                                       "v.nhdr");
    FAIL() << "a bad size was accepted";
  } catch (const base::Error& e) {
    EXPECT_EQ(e.where().file, "v.nhdr");
    EXPECT_EQ(e.where().line, 4);
    EXPECT_EQ(e.where().column, 10);  // the 'x'
    EXPECT_STREQ(e.what(), "v.nhdr:4:10: field 'sizes': 'x' is not a number");
  }
  try {
    renderers::scivis::parseMetaImageHeader("NDims = 3\n  DimSize = 4 4\nElementDataFile = LOCAL\n",
                                            "v.mhd");
    FAIL() << "two sizes were accepted";
  } catch (const base::Error& e) {
    EXPECT_STREQ(e.what(), "v.mhd:2:13: field 'DimSize': 3 numbers expected, found 2");
  }
  // ...and through the scene that names the file: the scene's place first, then the header's.
  const std::string header = writeFile("bad.nhdr", "NRRD0004\ntype: uchar\nsizes: 4 x 4\n\n");
  const std::string text =
      "[camera]\nposition = [0, 0, -5]\nlook_at = [0, 0, 0]\n"
      "[[volumes]]\nname = \"v\"\nsource = \"file\"\nfile = \"bad.nhdr\"\n"
      "transfer_function = { preset = \"viridis\", range = [0, 1] }\n";
  const std::string path = writeFile("header-scene.toml", text);
  const std::string e = errorOf([&] { renderers::readSceneToml(path); });
  const std::vector<Printed> p = expectWellFormed(e, path, text);
  ASSERT_EQ(p.size(), 1u) << e;
  EXPECT_EQ(p[0].line, 7);
  EXPECT_EQ(p[0].column, 8);
  EXPECT_EQ(p[0].rest, "volume 'v'.file: " + header + ":3:10: field 'sizes': 'x' is not a number");
}

}  // namespace
