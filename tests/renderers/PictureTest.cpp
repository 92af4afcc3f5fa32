// Ready-made pictures (`dfbwall show`): reading PNG and JPEG, fitting and scaling into a window
// in exact integer arithmetic, numbered sequences, and the renderer that draws them as tiles.
#include <gtest/gtest.h>
#include <png.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "renderers/RenderScene.h"
#include "renderers/picture/PictureFile.h"
#include "renderers/picture/PictureFit.h"
#include "renderers/picture/PictureRenderer.h"
#include "renderers/picture/PictureSequence.h"

namespace renderers::picture {
namespace {

namespace fs = std::filesystem;

std::uint32_t rgba(std::uint32_t r, std::uint32_t g, std::uint32_t b, std::uint32_t a = 255) {
  return r | (g << 8) | (b << 16) | (a << 24);
}

// A folder of this test process's own (ctest runs tests side by side).
class PictureFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dfbwall-picture-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    base::setMemoryLimit(0);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string writePng(const std::string& name, const Picture& p) const {
    png_image image;
    std::memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    image.width = static_cast<png_uint_32>(p.width);
    image.height = static_cast<png_uint_32>(p.height);
    image.format = PNG_FORMAT_RGBA;
    EXPECT_TRUE(png_image_write_to_file(&image, path(name).c_str(), 0, p.rgba.data(), 0, nullptr));
    return path(name);
  }
  std::string writeJpeg(const std::string& name, const Picture& p) const {
    tjhandle tj = tjInitCompress();
    unsigned char* jpeg = nullptr;
    unsigned long size = 0;
    EXPECT_EQ(tjCompress2(tj, reinterpret_cast<const unsigned char*>(p.rgba.data()), p.width,
                          4 * p.width, p.height, TJPF_RGBA, &jpeg, &size, TJSAMP_444, 100, 0),
              0);
    std::ofstream(path(name), std::ios::binary).write(reinterpret_cast<char*>(jpeg), size);
    tjFree(jpeg);
    tjDestroy(tj);
    return path(name);
  }
  fs::path dir_;
};

Picture gradient(int w, int h) {
  Picture p{w, h, {}};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      p.rgba.push_back(rgba(static_cast<std::uint32_t>(x * 255 / std::max(1, w - 1)),
                            static_cast<std::uint32_t>(y * 255 / std::max(1, h - 1)), 77));
  return p;
}

TEST(PictureFit, KeepsTheAspectCentredAndRoundsOnce) {
  auto fits = [](int pw, int ph, int ww, int wh) {
    const Placement p = fitPicture(pw, ph, ww, wh);
    return std::vector<int>{p.x, p.y, p.width, p.height};
  };
  EXPECT_EQ(fits(100, 50, 200, 200), (std::vector<int>{0, 50, 200, 100}));
  EXPECT_EQ(fits(50, 100, 200, 200), (std::vector<int>{50, 0, 100, 200}));
  EXPECT_EQ(fits(40, 30, 400, 300), (std::vector<int>{0, 0, 400, 300}));
  // 97x61 into 250x170: as wide; 61 * 250 / 97 = 157.2 rounds to 157; margin 13: 6 above.
  EXPECT_EQ(fits(97, 61, 250, 170), (std::vector<int>{0, 6, 250, 157}));
  // A sliver keeps at least a pixel.
  EXPECT_EQ(fits(1, 1000, 100, 10), (std::vector<int>{49, 0, 1, 10}));
}

TEST(PictureFit, NearestAndBilinearAtTheSameSizeAreThePicture) {
  const Picture p = gradient(37, 23);
  const Placement at = fitPicture(37, 23, 37, 23);
  for (Filter f : {Filter::Nearest, Filter::Bilinear})
    for (int y = 0; y < 23; ++y)
      for (int x = 0; x < 37; ++x)
        ASSERT_EQ(fittedPixel(p, at, f, 0, x, y), p.rgba[static_cast<size_t>(y * 37 + x)]);
}

TEST(PictureFit, NearestDoublesAndBilinearWeighsExactly) {
  Picture p{2, 1, {rgba(0, 0, 0), rgba(255, 255, 255)}};
  const Placement at = fitPicture(2, 1, 4, 2);  // 4x2: the whole window
  ASSERT_EQ(at.width, 4);
  const std::uint32_t bg = rgba(1, 2, 3);
  std::vector<std::uint32_t> nearest, bilinear;
  for (int x = 0; x < 4; ++x) {
    nearest.push_back(fittedPixel(p, at, Filter::Nearest, bg, x, 1) & 0xff);
    bilinear.push_back(fittedPixel(p, at, Filter::Bilinear, bg, x, 1) & 0xff);
  }
  EXPECT_EQ(nearest, (std::vector<std::uint32_t>{0, 0, 255, 255}));
  // Centres at -1/4, 1/4, 3/4, 5/4 of the source: clamped, 255/4 = 63.75, 191.25, clamped.
  EXPECT_EQ(bilinear, (std::vector<std::uint32_t>{0, 64, 191, 255}));
  // Outside the placement: the background.
  const Placement letterboxed = fitPicture(2, 1, 4, 4);
  EXPECT_EQ(fittedPixel(p, letterboxed, Filter::Bilinear, bg, 0, 0), bg);
  EXPECT_EQ(fittedPixel(p, letterboxed, Filter::Bilinear, bg, 0, 3), bg);
  EXPECT_NE(fittedPixel(p, letterboxed, Filter::Bilinear, bg, 3, 2), bg);
}

// The row at a time path equals the pixel at a time definition, for both filters, up and down,
// in and out of the placement, from any column.
TEST(PictureFit, RowsEqualPixels) {
  std::uint32_t seed = 1;
  auto random = [&seed] { return seed = seed * 1664525u + 1013904223u; };
  for (const auto& [pw, ph, ww, wh] : std::vector<std::array<int, 4>>{{97, 61, 250, 170},
                                                                      {61, 97, 250, 170},
                                                                      {400, 300, 37, 29},
                                                                      {1, 1, 5, 3},
                                                                      {3, 1000, 64, 64},
                                                                      {640, 360, 1920, 1080}}) {
    Picture p{pw, ph, {}};
    for (int i = 0; i < pw * ph; ++i) p.rgba.push_back(random() | 0xff000000u);
    const auto shared = std::make_shared<const Picture>(p);
    for (Filter f : {Filter::Nearest, Filter::Bilinear}) {
      const FittedPicture fitted(shared, ww, wh, f, rgba(9, 8, 7));
      const Placement at = fitPicture(pw, ph, ww, wh);
      std::vector<std::uint32_t> row(static_cast<size_t>(ww));
      for (int y = 0; y < wh; y += std::max(1, wh / 40)) {
        const int x0 = y % 3 == 0 ? 0 : ww / 3;
        fitted.row(y, x0, ww, row.data());
        for (int x = x0; x < ww; ++x)
          ASSERT_EQ(row[static_cast<size_t>(x - x0)], fittedPixel(p, at, f, rgba(9, 8, 7), x, y))
              << pw << "x" << ph << " into " << ww << "x" << wh << " at " << x << "," << y;
      }
    }
  }
}

TEST(PictureFit, TransparencyShowsTheBackground) {
  Picture p{3, 1, {rgba(200, 100, 0, 0), rgba(200, 100, 0, 255), rgba(200, 100, 0, 128)}};
  flattenOver(p, rgba(0, 0, 255));
  EXPECT_EQ(p.rgba[0], rgba(0, 0, 255));
  EXPECT_EQ(p.rgba[1], rgba(200, 100, 0));
  // (200*128 + 127) / 255 = 100, (100*128 + 127) / 255 = 50, (255*127 + 127) / 255 = 127.
  EXPECT_EQ(p.rgba[2], rgba(100, 50, 127));
  EXPECT_THROW(filterFromName("cubic"), base::Error);
}

TEST_F(PictureFiles, PngAndJpegReadBack) {
  const Picture g = gradient(33, 17);
  const Picture png = readPicture(writePng("g.png", g));
  EXPECT_EQ(png.width, 33);
  EXPECT_EQ(png.rgba, g.rgba);
  // A JPEG named .png is still a JPEG: the first bytes decide.
  const std::string jpegFile = writeJpeg("g.png.jpg", g);
  const PictureHeader h = readPictureHeader(jpegFile);
  EXPECT_EQ(h.format, "JPEG");
  EXPECT_EQ(h.width, 33);
  const Picture jpeg = readPicture(jpegFile);
  ASSERT_EQ(jpeg.rgba.size(), g.rgba.size());
  for (size_t i = 0; i < g.rgba.size(); ++i)
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(int((jpeg.rgba[i] >> (8 * c)) & 0xff), int((g.rgba[i] >> (8 * c)) & 0xff), 3);
}

TEST_F(PictureFiles, BadFilesAreRefusedByName) {
  auto message = [](const std::string& file) {
    try {
      readPicture(file);
    } catch (const base::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(path("missing.png")).find("missing.png: cannot open the picture"),
            std::string::npos);
  std::ofstream(path("text.png")) << "not a picture\n";
  EXPECT_NE(message(path("text.png")).find("not a PNG or JPEG"), std::string::npos);
  // A PNG cut after its header: the header reads, the pixels do not.
  const std::string png = writePng("whole.png", gradient(64, 64));
  const auto size = fs::file_size(png);
  fs::copy_file(png, path("cut.png"));
  fs::resize_file(path("cut.png"), size / 2);
  EXPECT_EQ(readPictureHeader(path("cut.png")).width, 64);
  EXPECT_NE(message(path("cut.png")).find("a corrupt PNG"), std::string::npos);
  const std::string jpeg = writeJpeg("whole.jpg", gradient(64, 64));
  fs::copy_file(jpeg, path("cut.jpg"));
  fs::resize_file(path("cut.jpg"), fs::file_size(jpeg) / 2);
  EXPECT_NE(message(path("cut.jpg")).find("a corrupt JPEG"), std::string::npos);
  // Larger than this process may hold: refused from the header, naming the size.
  base::setMemoryLimit(4096);
  EXPECT_NE(message(png).find("the 64x64 picture needs"), std::string::npos) << message(png);
  EXPECT_THROW(readPictureHeader(png), base::Error);
}

TEST_F(PictureFiles, NumberedSequences) {
  for (int i : {7, 8, 9, 10})
    writePng("p-" + std::string(i < 10 ? "000" : "00") + std::to_string(i) + ".png",
             gradient(2, 2));
  writePng("p-00011.png", gradient(2, 2));  // not what %04d writes for 11
  writePng("single.png", gradient(2, 2));
  const std::vector<std::string> files =
      expandPictures({path("single.png"), path("p-%04d.png"), path("single.png")});
  ASSERT_EQ(files.size(), 6u);
  EXPECT_EQ(files[1], path("p-0007.png"));
  EXPECT_EQ(files[4], path("p-0010.png"));
  EXPECT_EQ(files[5], path("single.png"));
  auto message = [](const std::vector<std::string>& arguments) {
    try {
      expandPictures(arguments);
    } catch (const base::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  fs::remove(path("p-0008.png"));
  EXPECT_NE(message({path("p-%04d.png")}).find("gap: " + path("p-0008.png") + " is missing"),
            std::string::npos)
      << message({path("p-%04d.png")});
  EXPECT_NE(message({path("q-%d.png")}).find("no file in"), std::string::npos);
  EXPECT_NE(message({path("nope.png")}).find("nope.png: no such file"), std::string::npos);
  EXPECT_NE(message({path("p-%d-%d.png")}).find("one number field"), std::string::npos);
  EXPECT_NE(message({path("p-%s.png")}).find("%d or %0Nd"), std::string::npos);
  // %% is a literal %: the sequence is looked for, and not found.
  EXPECT_NE(message({path("100%%-%d.png")}).find("no file in"), std::string::npos);
}

TEST(PictureSequence, WhichPictureAFrameShows) {
  EXPECT_EQ(pictureOfFrame(1, 3, false), 0u);
  EXPECT_EQ(pictureOfFrame(3, 3, false), 2u);
  EXPECT_EQ(pictureOfFrame(9, 3, false), 2u);  // held
  EXPECT_EQ(pictureOfFrame(4, 3, true), 0u);   // looped
  EXPECT_EQ(pictureOfFrame(8, 3, true), 1u);
  EXPECT_EQ(pictureOfFrame(5, 1, true), 0u);
}

// The renderer: display pixels only, the same whatever the tiles, the picture of the frame.
TEST_F(PictureFiles, RendererDrawsTheFittedPictureOfEachFrame) {
  registerPictures();
  PictureDesc desc;
  desc.files = {writePng("a.png", gradient(40, 20)), writePng("b.png", gradient(10, 30))};
  desc.background = rgba(10, 20, 30);
  desc.filter = Filter::Bilinear;
  const RenderScene scene = buildRenderScene(kPictureName, pictureScene(desc));
  RenderSettings settings;
  settings.width = 90;
  settings.height = 70;
  const std::unique_ptr<Renderer> renderer = makeRenderer(kPictureName, scene, settings);
  auto draw = [&](int tile) {
    std::vector<std::uint32_t> image(90 * 70);
    for (int y0 = 0; y0 < 70; y0 += tile)
      for (int x0 = 0; x0 < 90; x0 += tile) {
        const dfb::Region r{x0, y0, std::min(x0 + tile, 90), std::min(y0 + tile, 70)};
        dfb::Tile t;
        renderer->render(r, 0, 0, 1, t);
        EXPECT_TRUE(t.color.empty());
        size_t i = 0;
        for (int y = r.y0; y < r.y1; ++y)
          for (int x = r.x0; x < r.x1; ++x) image[static_cast<size_t>(y * 90 + x)] = t.rgba8[i++];
      }
    return image;
  };
  auto expected = [&](const std::string& file) {
    Picture p = readPicture(file);
    flattenOver(p, desc.background);
    const Placement at = fitPicture(p.width, p.height, 90, 70);
    std::vector<std::uint32_t> image;
    for (int y = 0; y < 70; ++y)
      for (int x = 0; x < 90; ++x)
        image.push_back(fittedPixel(p, at, desc.filter, desc.background, x, y));
    return image;
  };
  renderer->beginFrame({1, 0}, {});
  EXPECT_EQ(draw(64), expected(desc.files[0]));
  EXPECT_EQ(draw(16), expected(desc.files[0]));
  renderer->beginFrame({2, 0}, {});
  EXPECT_EQ(draw(64), expected(desc.files[1]));
  renderer->beginFrame({3, 0}, {});  // held: no loop
  EXPECT_EQ(draw(32), expected(desc.files[1]));
  // A file the header check refuses fails the scene's build, not a later frame.
  std::ofstream(path("bad.png")) << "nothing";
  desc.files.push_back(path("bad.png"));
  EXPECT_THROW(buildRenderScene(kPictureName, pictureScene(desc)), base::Error);
}

}  // namespace
}  // namespace renderers::picture
