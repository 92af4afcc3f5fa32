// What composing a shared display costs the wall process's presenting thread
// (wall/display/WindowStack.h): a 1920x1080 display with 1, 2 or 4 overlapping windows, composed
// by spans (each pixel written once: the top window's or the background), beside the painter's way
// (background, then every window over it in order) and a plain copy of one frame (the floor). Also
// a whole display frame through WindowStack: a job's swap of a window across the display, then
// compose(). And what a window's thumbnail costs once a second (wall/image/Thumbnail.h): a
// process summing one display's part of a 3840x2160 window (factor 12, 320x180 cells), and the
// head averaging the cells. Prints ms per display frame (median of runs) and writes JSON (argv[1],
// default bench/results/composition.json). Goal: <= 2 ms per 1080p display.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "wall/display/WindowStack.h"
#include "wall/image/Image.h"
#include "wall/image/Thumbnail.h"

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kWidth = 1920, kHeight = 1080;
constexpr std::uint32_t kBackground = 0xff000000u;

// Median ms of `runs` calls, after two warm-up calls.
double medianMs(int runs, const std::function<void()>& work) {
  work();
  work();
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = Clock::now();
    work();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

wall::Image imageOf(const dfb::Region& part, std::uint32_t seed) {
  wall::Image image(part.width(), part.height());
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = 0xff000000u | static_cast<std::uint32_t>(i * 2654435761u + seed) >> 8;
  return image;
}

void painters(wall::Image& frame, const std::vector<wall::ComposedLayer>& layers) {
  std::fill(frame.pixels.begin(), frame.pixels.end(), kBackground);
  for (const wall::ComposedLayer& l : layers)
    for (int y = 0; y < l.part.height(); ++y)
      std::copy_n(
          l.pixels->pixels.begin() + static_cast<std::ptrdiff_t>(y) * l.part.width(),
          l.part.width(),
          frame.pixels.begin() + static_cast<std::ptrdiff_t>(l.part.y0 + y) * kWidth + l.part.x0);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "bench/results/composition.json";
  const int runs = 101;
  const std::vector<std::pair<std::string, std::vector<dfb::Region>>> stacks = {
      {"1 window (the whole display)", {{0, 0, kWidth, kHeight}}},
      {"2 windows (overlapping)", {{0, 0, 1280, 720}, {640, 360, 1920, 1080}}},
      {"4 windows (overlapping quarters)",
       {{0, 0, 1100, 640}, {820, 0, 1920, 640}, {0, 440, 1100, 1080}, {820, 440, 1920, 1080}}},
  };
  wall::Image frame(kWidth, kHeight), copy(kWidth, kHeight, 1);
  const double floorMs = medianMs(
      runs, [&] { std::copy(copy.pixels.begin(), copy.pixels.end(), frame.pixels.begin()); });
  std::printf("composition of one %dx%d display (median of %d, ms per display frame)\n", kWidth,
              kHeight, runs);
  std::printf("  copy of one frame (the floor): %.3f ms\n", floorMs);
  std::string rows;
  for (const auto& [name, parts] : stacks) {
    std::vector<wall::Image> images;
    images.reserve(parts.size());
    std::vector<wall::ComposedLayer> layers;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      images.push_back(imageOf(parts[i], static_cast<std::uint32_t>(i)));
      layers.push_back({parts[i], &images.back()});
    }
    const double spans = medianMs(runs, [&] { wall::composeLayers(frame, kBackground, layers); });
    const double painter = medianMs(runs, [&] { painters(frame, layers); });
    // Through the stack: one job's window over each part (as a node swaps), then compose().
    wall::WindowStack stack({{kWidth, kHeight}}, kBackground);
    std::vector<std::unique_ptr<wall::WindowStack::Window>> windows;
    for (const dfb::Region& part : parts) windows.push_back(stack.add({part}));
    for (std::size_t i = 0; i < parts.size(); ++i) {
      wall::Presenter& layer = *windows[i]->presenters()[0];
      layer.present(images[i].pixels.data(), images[i].width, images[i].height);
    }
    stack.compose();
    wall::Presenter& top = *windows.back()->presenters()[0];
    const wall::Image& topImage = images.back();
    const double swapMs = medianMs(runs, [&] {
      top.beginFrame(topImage.width, topImage.height);
      top.upload(topImage.pixels.data(), topImage.width, {0, 0, topImage.width, topImage.height});
      top.swap();
    });
    const double stackMs = medianMs(runs, [&] {
      top.swap();  // the same frame again: the display changed
      stack.compose();
    });
    std::printf(
        "  %-34s spans %.3f ms, painter's %.3f ms; a job's upload+swap %.3f ms, "
        "swap+compose %.3f ms\n",
        name.c_str(), spans, painter, swapMs, stackMs);
    rows += std::string(rows.empty() ? "" : ",") + "\n    {\"stack\": \"" + name +
            "\", \"windows\": " + std::to_string(parts.size()) +
            ", \"spans_ms\": " + std::to_string(spans) +
            ", \"painters_ms\": " + std::to_string(painter) +
            ", \"job_upload_swap_ms\": " + std::to_string(swapMs) +
            ", \"swap_compose_ms\": " + std::to_string(stackMs) + "}";
  }
  // A thumbnail: this display is the top-left quarter of a 3840x2160 window.
  const wall::ThumbnailGrid grid = wall::thumbnailGrid(2 * kWidth, 2 * kHeight, 320);
  const wall::Image part = imageOf({0, 0, kWidth, kHeight}, 1);
  wall::CellSums sums = wall::emptySums(wall::cellsOf(grid, {0, 0, kWidth, kHeight}));
  const double thumbnailSumsMs = medianMs(runs, [&] {
    std::fill(sums.sums.begin(), sums.sums.end(), 0u);
    wall::addPixels(sums, grid, part, 0, 0);
  });
  wall::CellSums whole = wall::emptySums({0, 0, grid.width, grid.height});
  const double thumbnailAverageMs =
      medianMs(runs, [&] { wall::averageCells(grid, whole, nullptr); });
  std::printf(
      "  thumbnail (%dx%d cells, factor %d): a display's sums %.3f ms, the head's average "
      "%.3f ms (once a second each)\n",
      grid.width, grid.height, grid.factor, thumbnailSumsMs, thumbnailAverageMs);
  std::ofstream json(out);
  json << "{\"figure\": \"composition\", \"display\": \"" << kWidth << "x" << kHeight
       << "\", \"runs\": " << runs << ", \"threads\": " << std::thread::hardware_concurrency()
       << ", \"copy_floor_ms\": " << floorMs << ", \"goal\": \"<= 2 ms per 1080p display\","
       << " \"thumbnail_display_sums_ms\": " << thumbnailSumsMs
       << ", \"thumbnail_average_ms\": " << thumbnailAverageMs << ","
       << "\n \"results\": [" << rows << "\n ]}\n";
  if (!json) {
    std::fprintf(stderr, "composition_bench: cannot write %s\n", out.c_str());
    return 1;
  }
  std::printf("written: %s\n", out.c_str());
  return 0;
}
