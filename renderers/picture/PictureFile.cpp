#include "renderers/picture/PictureFile.h"

#include <png.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

#include "base/Error.h"
#include "base/MemoryBudget.h"

namespace renderers::picture {
namespace {

// A JPEG file's bytes are held whole while decoding; bounded like the pixels.
std::vector<unsigned char> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw base::Error(path + ": cannot open the picture: " + std::strerror(errno));
  const std::streamoff size = in.tellg();
  if (size < 0) throw base::Error(path + ": cannot read the picture");
  if (std::string problem = base::memoryProblem(static_cast<std::uint64_t>(size)); !problem.empty())
    throw base::Error(path + ": the file " + problem);
  std::vector<unsigned char> bytes(static_cast<size_t>(size));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), size))
    throw base::Error(path + ": cannot read the picture");
  return bytes;
}

std::string formatOf(const std::string& path) {
  FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw base::Error(path + ": cannot open the picture: " + std::strerror(errno));
  unsigned char magic[8] = {};
  const size_t n = std::fread(magic, 1, sizeof magic, file);
  std::fclose(file);
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n == 8 && std::memcmp(magic, kPng, 8) == 0) return "PNG";
  if (n >= 3 && magic[0] == 0xff && magic[1] == 0xd8 && magic[2] == 0xff) return "JPEG";
  throw base::Error(path + ": not a PNG or JPEG picture (its first bytes are neither)");
}

void checkSize(const std::string& path, const PictureHeader& h) {
  if (h.width <= 0 || h.height <= 0 || h.width > kMaxPictureSide || h.height > kMaxPictureSide)
    throw base::Error(path + ": a " + std::to_string(h.width) + "x" + std::to_string(h.height) +
                      " picture; each side must be 1 to " + std::to_string(kMaxPictureSide));
  const std::uint64_t bytes = base::bytesTimes(
      base::bytesTimes(static_cast<std::uint64_t>(h.width), static_cast<std::uint64_t>(h.height)),
      4);
  if (std::string problem = base::memoryProblem(bytes); !problem.empty())
    throw base::Error(path + ": the " + std::to_string(h.width) + "x" + std::to_string(h.height) +
                      " picture " + problem);
}

struct PngReader {
  png_image image;
  explicit PngReader(const std::string& path) {
    std::memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&image, path.c_str()))
      throw base::Error(path + ": not a readable PNG: " + image.message);
  }
  ~PngReader() { png_image_free(&image); }
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;
};

struct Decompressor {
  tjhandle handle = tjInitDecompress();
  Decompressor() {
    if (!handle) throw base::Error("cannot start TurboJPEG's decompressor");
  }
  ~Decompressor() { tjDestroy(handle); }
  Decompressor(const Decompressor&) = delete;
  Decompressor& operator=(const Decompressor&) = delete;
};

PictureHeader jpegHeader(const std::string& path, const std::vector<unsigned char>& bytes,
                         Decompressor& tj) {
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  if (tjDecompressHeader3(tj.handle, bytes.data(), static_cast<unsigned long>(bytes.size()), &width,
                          &height, &subsampling, &colorspace) != 0)
    throw base::Error(path + ": not a readable JPEG: " + tjGetErrorStr2(tj.handle));
  PictureHeader h{width, height, "JPEG"};
  checkSize(path, h);
  return h;
}

}  // namespace

PictureHeader readPictureHeader(const std::string& path) {
  const std::string format = formatOf(path);
  if (format == "PNG") {
    PngReader png(path);
    PictureHeader h{static_cast<int>(std::min<png_uint_32>(png.image.width, 1u << 30)),
                    static_cast<int>(std::min<png_uint_32>(png.image.height, 1u << 30)), format};
    checkSize(path, h);
    return h;
  }
  Decompressor tj;
  return jpegHeader(path, readBytes(path), tj);
}

Picture readPicture(const std::string& path) {
  const std::string format = formatOf(path);
  Picture out;
  if (format == "PNG") {
    PngReader png(path);
    const PictureHeader h{static_cast<int>(std::min<png_uint_32>(png.image.width, 1u << 30)),
                          static_cast<int>(std::min<png_uint_32>(png.image.height, 1u << 30)),
                          format};
    checkSize(path, h);
    png.image.format = PNG_FORMAT_RGBA;
    out.width = h.width, out.height = h.height;
    out.rgba.resize(static_cast<size_t>(h.width) * static_cast<size_t>(h.height));
    if (!png_image_finish_read(&png.image, nullptr, out.rgba.data(), 0, nullptr))
      throw base::Error(path + ": a corrupt PNG: " + png.image.message);
    return out;
  }
  const std::vector<unsigned char> bytes = readBytes(path);
  Decompressor tj;
  const PictureHeader h = jpegHeader(path, bytes, tj);
  out.width = h.width, out.height = h.height;
  out.rgba.resize(static_cast<size_t>(h.width) * static_cast<size_t>(h.height));
  // Accurate DCT and fancy upsampling: libjpeg's defaults, so other decoders agree.
  if (tjDecompress2(tj.handle, bytes.data(), static_cast<unsigned long>(bytes.size()),
                    reinterpret_cast<unsigned char*>(out.rgba.data()), h.width, 4 * h.width,
                    h.height, TJPF_RGBA, 0) != 0)  // a warning too: a truncated file
    throw base::Error(path + ": a corrupt JPEG: " + tjGetErrorStr2(tj.handle));
  return out;
}

}  // namespace renderers::picture
