// A serving wall's own captures (wall/display/WallCaptures.h) on a real offscreen presenter and
// real files: every K-th wall frame is written, from the writer's thread, as what the display
// showed; a quota that is spent stops the captures with a line in the log, never the caller.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "wall/display/OsmesaPresenter.h"
#include "wall/display/WallCaptures.h"
#include "wall/image/Png.h"

namespace {

namespace fs = std::filesystem;

wall::Image noise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  wall::Image img(w, h);
  for (auto& p : img.pixels) p = static_cast<std::uint32_t>(rng()) | 0xff000000u;
  return img;
}

struct Folder {
  fs::path path;
  explicit Folder(const char* name)
      : path(fs::temp_directory_path() / (name + std::string("-") + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Folder() { fs::remove_all(path); }
};

wall::Layout twoByTwo() {
  return wall::loadLayout(std::string(DFBWALL_SOURCE_DIR) + "/configs/walls/2x2.toml");
}

TEST(WallCaptures, EveryKthWallFrameAsTheDisplayShowedIt) {
  const wall::Layout layout = twoByTwo();
  const wall::Display& d = layout.displays[static_cast<size_t>(layout.displaysOfProcess(0)[0])];
  auto display = wall::makeOsmesaPresenter(d.rect.width(), d.rect.height());
  Folder dir("dfbwall-wall-captures-test");
  auto root = std::make_shared<const base::ConfinedFolder>(dir.path.string(), "the folder");
  ASSERT_EQ(wall::checkWallCaptureFolders(*root, layout, 0), "");
  std::vector<std::string> log;
  std::vector<wall::Image> shown;
  {
    wall::WallCaptures captures(layout, 0, {display.get()}, root, 2, 0,
                                [&log](const std::string& line) { log.push_back(line); });
    for (unsigned frame = 1; frame <= 5; ++frame) {
      shown.push_back(noise(d.rect.width(), d.rect.height(), frame));
      display->present(shown.back().pixels.data(), d.rect.width(), d.rect.height());
      captures.presented(frame);
    }
  }  // the destructor writes what is queued
  EXPECT_EQ(log.size(), 0u);
  for (unsigned frame = 1; frame <= 5; ++frame) {
    SCOPED_TRACE(frame);
    const std::string path = wall::displayCapturePath(dir.path.string(), d.name, frame);
    ASSERT_EQ(fs::exists(path), frame % 2 == 0);
    if (frame % 2 == 0) {
      EXPECT_TRUE(wall::readPng(path) == shown[frame - 1]);
    }
  }
  // Written then renamed: no temporary is left beside the captures.
  size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir.path))
    files += entry.is_regular_file();
  EXPECT_EQ(files, 2u);
}

TEST(WallCaptures, ASpentQuotaStopsTheCapturesNotTheWall) {
  const wall::Layout layout = twoByTwo();
  const wall::Display& d = layout.displays[static_cast<size_t>(layout.displaysOfProcess(0)[0])];
  auto display = wall::makeOsmesaPresenter(d.rect.width(), d.rect.height());
  Folder dir("dfbwall-wall-captures-quota-test");
  auto root = std::make_shared<const base::ConfinedFolder>(dir.path.string(), "the folder");
  std::mutex mutex;
  std::vector<std::string> log;
  wall::WallCaptures captures(layout, 0, {display.get()}, root, 1, 100, [&](const std::string& l) {
    std::lock_guard lock(mutex);
    log.push_back(l);
  });
  // More frames than the queue holds: once the first fails, none waits for the writer.
  for (unsigned frame = 1; frame <= 3 * wall::WallCaptures::kMaxQueued; ++frame) {
    const wall::Image image = noise(d.rect.width(), d.rect.height(), frame);
    display->present(image.pixels.data(), image.width, image.height);
    captures.presented(frame);
  }
  captures.flush();
  std::lock_guard lock(mutex);
  ASSERT_EQ(log.size(), 1u);
  EXPECT_NE(log[0].find("the wall's captures would pass the capture quota"), std::string::npos)
      << log[0];
  size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir.path))
    files += entry.is_regular_file();
  EXPECT_EQ(files, 0u);
}

}  // namespace
