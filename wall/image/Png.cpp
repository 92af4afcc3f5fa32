#include "wall/image/Png.h"

#include <png.h>

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "base/AtomicFile.h"
#include "base/Error.h"

namespace wall {
namespace {
void writeAtomically(const std::string& path, const std::uint32_t* rgba8, int width, int height);
}  // namespace

// libpng's PNG_FORMAT_RGBA is bytes R, G, B, A: our uint32 layout only on little-endian hosts.
static_assert(std::endian::native == std::endian::little,
              "wall/ stores RGBA8 with R in the low byte and hands it to libpng as bytes");

void writePng(const std::string& path, const std::uint32_t* rgba8, int width, int height) {
  if (width <= 0 || height <= 0)
    throw base::Error(path + ": cannot write a " + std::to_string(width) + "x" +
                      std::to_string(height) + " PNG");
  writeAtomically(path, rgba8, width, height);
}

void writePngTo(std::FILE* stream, const std::string& path, const std::uint32_t* rgba8, int width,
                int height) {
  if (width <= 0 || height <= 0)
    throw base::Error(path + ": cannot write a " + std::to_string(width) + "x" +
                      std::to_string(height) + " PNG");
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGBA;
  errno = 0;
  const int written = png_image_write_to_stdio(&image, stream, 0, rgba8, 0, nullptr);
  const int error = errno;  // libpng says only "Write Error"; the cause (ENOSPC) is in errno
  const std::string message = image.message;
  png_image_free(&image);
  if (!written)
    throw base::Error(path + ": cannot write the PNG: " + message +
                      (error ? std::string(": ") + std::strerror(error) : std::string()));
}

namespace {
void writeAtomically(const std::string& path, const std::uint32_t* rgba8, int width, int height) {
  base::AtomicFile file(path);
  writePngTo(file.stream(), path, rgba8, width, height);
  file.commit();  // a full disk shows here (base::Error, naming the path)
}
}  // namespace

std::string encodePng(const Image& image) {
  if (image.width <= 0 || image.height <= 0)
    throw base::Error("cannot encode an empty image as PNG");
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGBA;
  // libpng's simplified API: a first call sizes the buffer, the second fills it.
  png_alloc_size_t size = 0;
  std::string out;
  if (png_image_write_to_memory(&png, nullptr, &size, 0, image.pixels.data(), 0, nullptr)) {
    out.resize(size);
    if (png_image_write_to_memory(&png, out.data(), &size, 0, image.pixels.data(), 0, nullptr)) {
      out.resize(size);
      png_image_free(&png);
      return out;
    }
  }
  const std::string message = png.message;
  png_image_free(&png);
  throw base::Error("cannot encode a PNG in memory: " + message);
}

Image readPng(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str()))
    throw base::Error(path + ": cannot read the PNG: " + image.message);
  image.format = PNG_FORMAT_RGBA;
  Image out(static_cast<int>(image.width), static_cast<int>(image.height));
  if (!png_image_finish_read(&image, nullptr, out.pixels.data(), 0, nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    throw base::Error(path + ": cannot decode the PNG: " + message);
  }
  return out;
}

}  // namespace wall
