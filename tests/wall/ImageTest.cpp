// PNG files round-trip exactly and appear whole; capture paths and the wall preview.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>

#include "base/Error.h"
#include "wall/display/Capture.h"
#include "wall/image/Image.h"
#include "wall/image/Png.h"
#include "wall/layout/Layout.h"

namespace fs = std::filesystem;

namespace {

// A fresh folder per test, removed afterwards.
class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dfbwall-wall-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::vector<std::string> filesIn(const fs::path& d) const {
    std::vector<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(d))
      out.push_back(fs::relative(e.path(), dir_).string());
    std::sort(out.begin(), out.end());
    return out;
  }
  fs::path dir_;
};

wall::Image noise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  wall::Image img(w, h);
  for (auto& p : img.pixels) p = static_cast<std::uint32_t>(rng());  // alpha varies too
  return img;
}

using Png = TempDir;

TEST_F(Png, RoundTripIsExactAndLeavesNoTemporaryFile) {
  const wall::Image img = noise(123, 77, 1);
  const std::string path = (dir_ / "a.png").string();
  wall::writePng(path, img);
  EXPECT_EQ(filesIn(dir_), std::vector<std::string>{"a.png"});
  const wall::Image back = wall::readPng(path);
  EXPECT_EQ(back.width, 123);
  EXPECT_EQ(back.height, 77);
  EXPECT_TRUE(back == img);
  // Overwriting replaces the file whole.
  const wall::Image other = noise(5, 3, 2);
  wall::writePng(path, other);
  EXPECT_TRUE(wall::readPng(path) == other);
  EXPECT_EQ(filesIn(dir_), std::vector<std::string>{"a.png"});
}

TEST_F(Png, ByteOrderIsRGBA) {
  const wall::Image img(1, 1, wall::rgba8(10, 20, 30, 40));
  const std::string path = (dir_ / "one.png").string();
  wall::writePng(path, img);
  const wall::Image back = wall::readPng(path);
  EXPECT_EQ(back.at(0, 0) & 0xffu, 10u);
  EXPECT_EQ(back.at(0, 0) >> 24, 40u);
}

TEST_F(Png, FailuresNameTheFileAndLeaveNothing) {
  EXPECT_THROW(wall::readPng((dir_ / "missing.png").string()), base::Error);
  const wall::Image img = noise(4, 4, 3);
  try {
    wall::writePng((dir_ / "no-such-dir" / "x.png").string(), img);
    FAIL() << "no exception";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(wall::writePng((dir_ / "empty.png").string(), nullptr, 0, 5), base::Error);
  EXPECT_TRUE(filesIn(dir_).empty());
}

using Capture = TempDir;

TEST_F(Capture, PathsFollowTheLayout) {
  EXPECT_EQ(wall::displayCapturePath("out", "r0c1", 7), "out/r0c1/frame-000007.png");
  EXPECT_EQ(wall::wallPreviewPath("out", 123456), "out/wall-123456.png");
  EXPECT_EQ(wall::wallPreviewPath("out", 1234567), "out/wall-1234567.png");
}

TEST_F(Capture, DisplayCaptureAndPreview) {
  const wall::Layout l =
      wall::loadLayout(std::string(DFBWALL_SOURCE_DIR) + "/configs/walls/2x2.toml");
  std::vector<wall::Image> frames;
  std::vector<const std::uint32_t*> pointers;
  for (size_t i = 0; i < l.displays.size(); ++i) {
    frames.push_back(noise(l.displays[i].rect.width(), l.displays[i].rect.height(), 10 + i));
    pointers.push_back(frames.back().pixels.data());
  }
  for (size_t i = 0; i < l.displays.size(); ++i) {
    const std::string path =
        wall::writeDisplayCapture(dir_.string(), l, static_cast<int>(i), 42, pointers[i]);
    EXPECT_EQ(path, wall::displayCapturePath(dir_.string(), l.displays[i].name, 42));
    EXPECT_TRUE(wall::readPng(path) == frames[i]);
  }
  const wall::Image preview = wall::composeWallPreview(l, pointers);
  ASSERT_EQ(preview.width, l.canvasWidth);
  ASSERT_EQ(preview.height, l.canvasHeight);
  for (size_t i = 0; i < l.displays.size(); ++i)
    EXPECT_TRUE(wall::crop(preview, l.displays[i].rect) == frames[i]) << l.displays[i].name;
  // Bezel pixels: between the columns (x 200..212) and between the rows (y 150..160).
  EXPECT_EQ(preview.at(205, 20), wall::kBezelColor);
  EXPECT_EQ(preview.at(20, 155), wall::kBezelColor);
  EXPECT_EQ(preview.at(206, 155), wall::kBezelColor);
  wall::writePng(wall::wallPreviewPath(dir_.string(), 42), preview);
  EXPECT_EQ(filesIn(dir_),
            (std::vector<std::string>{"r0c0", "r0c0/frame-000042.png", "r0c1",
                                      "r0c1/frame-000042.png", "r1c0", "r1c0/frame-000042.png",
                                      "r1c1", "r1c1/frame-000042.png", "wall-000042.png"}));
  // A display without a frame stays dark.
  pointers[1] = nullptr;
  const wall::Image partial = wall::composeWallPreview(l, pointers);
  EXPECT_EQ(partial.at(300, 50), wall::kBezelColor);
  EXPECT_THROW(wall::composeWallPreview(l, {}), base::Error);
}

TEST(ImageOps, CropAndBlit) {
  wall::Image canvas(10, 8, 0);
  const wall::Image patch = noise(3, 2, 5);
  wall::blit(canvas, 6, 5, patch.pixels.data(), 3, 2);
  EXPECT_TRUE(wall::crop(canvas, {6, 5, 9, 7}) == patch);
  EXPECT_EQ(canvas.at(5, 5), 0u);
  EXPECT_THROW(wall::blit(canvas, 8, 5, patch.pixels.data(), 3, 2), base::Error);
  EXPECT_THROW(wall::crop(canvas, {0, 0, 11, 1}), base::Error);
}

}  // namespace
