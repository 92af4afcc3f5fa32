// What `dfbwall show` spends per picture on one thread (renderers/picture/): decoding a 1080p PNG
// and JPEG (a smooth, plot-like picture with noise), and fitting a picture into a window with
// each filter, downscaling 3840x2160 into 1920x1080 and upscaling 640x360 into it, as ns per
// window pixel. Tells whether a sequence keeps up with its --fps on a render host. Prints a table
// and writes JSON (argv[1], default bench/results/picture.json). Fitting is timed twice: a pixel
// at a time (fittedPixel, the definition) and a row at a time (FittedPicture, what the renderer
// draws with).
#include <png.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "renderers/picture/PictureFile.h"
#include "renderers/picture/PictureFit.h"

namespace {

using Clock = std::chrono::steady_clock;
using renderers::picture::Filter;
using renderers::picture::Picture;

Picture makePicture(int w, int h) {
  std::mt19937 random(37);
  std::uniform_int_distribution<int> noise(-6, 6);
  Picture p{w, h, {}};
  p.rgba.reserve(static_cast<size_t>(w) * static_cast<size_t>(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int r = std::clamp(x * 255 / w + noise(random), 0, 255);
      const int g = std::clamp(y * 255 / h + noise(random), 0, 255);
      const int b = ((x / 96 + y / 96) & 1) ? 200 : 40;
      p.rgba.push_back(static_cast<std::uint32_t>(r | (g << 8) | (b << 16)) | 0xff000000u);
    }
  return p;
}

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The best of `runs` timings of `work`, in ms.
template <class Work>
double best(int runs, Work work) {
  double out = 1e30;
  for (int i = 0; i < runs; ++i) {
    const auto start = Clock::now();
    work();
    out = std::min(out, msSince(start));
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string output = argc > 1 ? argv[1] : "bench/results/picture.json";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("picture-bench-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Picture hd = makePicture(1920, 1080);
  const std::string png = (dir / "hd.png").string(), jpeg = (dir / "hd.jpg").string();
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = 1920;
  image.height = 1080;
  image.format = PNG_FORMAT_RGBA;
  png_image_write_to_file(&image, png.c_str(), 0, hd.rgba.data(), 0, nullptr);
  tjhandle tj = tjInitCompress();
  unsigned char* bytes = nullptr;
  unsigned long size = 0;
  tjCompress2(tj, reinterpret_cast<const unsigned char*>(hd.rgba.data()), 1920, 4 * 1920, 1080,
              TJPF_RGBA, &bytes, &size, TJSAMP_420, 90, 0);
  std::ofstream(jpeg, std::ios::binary).write(reinterpret_cast<const char*>(bytes), size);
  tjFree(bytes);
  tjDestroy(tj);

  const double pngMs = best(5, [&] { renderers::picture::readPicture(png); });
  const double jpegMs = best(5, [&] { renderers::picture::readPicture(jpeg); });
  std::printf(
      "decode 1920x1080 (one thread):  PNG %.1f ms (%ju bytes)   JPEG q90 4:2:0 %.1f ms "
      "(%lu bytes)\n",
      pngMs, static_cast<std::uintmax_t>(std::filesystem::file_size(png)), jpegMs, size);

  struct Case {
    const char* name;
    int sourceWidth, sourceHeight;
    Filter filter;
    double nsPerPixel = 0, rowNsPerPixel = 0;
  };
  std::vector<Case> cases = {{"3840x2160 -> 1920x1080 nearest", 3840, 2160, Filter::Nearest},
                             {"3840x2160 -> 1920x1080 bilinear", 3840, 2160, Filter::Bilinear},
                             {"640x360 -> 1920x1080 nearest", 640, 360, Filter::Nearest},
                             {"640x360 -> 1920x1080 bilinear", 640, 360, Filter::Bilinear}};
  std::vector<std::uint32_t> window(1920 * 1080);
  for (Case& c : cases) {
    const Picture source = makePicture(c.sourceWidth, c.sourceHeight);
    const auto at = renderers::picture::fitPicture(source.width, source.height, 1920, 1080);
    const double ms = best(3, [&] {
      for (int y = 0; y < 1080; ++y)
        for (int x = 0; x < 1920; ++x)
          window[static_cast<size_t>(y) * 1920 + static_cast<size_t>(x)] =
              renderers::picture::fittedPixel(source, at, c.filter, 0xff000000u, x, y);
    });
    const renderers::picture::FittedPicture fitted(std::make_shared<const Picture>(source), 1920,
                                                   1080, c.filter, 0xff000000u);
    const double rowMs = best(3, [&] {
      for (int y = 0; y < 1080; ++y) fitted.row(y, 0, 1920, window.data() + y * 1920);
    });
    c.nsPerPixel = ms * 1e6 / (1920.0 * 1080.0);
    c.rowNsPerPixel = rowMs * 1e6 / (1920.0 * 1080.0);
    std::printf("fit %-32s pixels %6.2f ns (%5.1f ms a 1080p frame)  rows %6.2f ns (%5.1f ms)\n",
                c.name, c.nsPerPixel, ms, c.rowNsPerPixel, rowMs);
  }
  std::filesystem::remove_all(dir);

  std::filesystem::create_directories(std::filesystem::path(output).parent_path());
  std::ofstream json(output);
  json << "{\"decode_ms\": {\"png_1080p\": " << pngMs << ", \"jpeg_1080p\": " << jpegMs
       << "}, \"fit_ns_per_pixel\": {";
  for (size_t i = 0; i < cases.size(); ++i)
    json << (i ? ", " : "") << "\"" << cases[i].name << "\": {\"pixels\": " << cases[i].nsPerPixel
         << ", \"rows\": " << cases[i].rowNsPerPixel << "}";
  json << "}}\n";
  std::printf("wrote %s\n", output.c_str());
  return 0;
}
