#include "wall/Png.h"

#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "wall/Error.h"

namespace wall {

// libpng's PNG_FORMAT_RGBA is bytes R, G, B, A: our uint32 layout only on little-endian hosts.
static_assert(std::endian::native == std::endian::little,
              "wall/ stores RGBA8 with R in the low byte and hands it to libpng as bytes");

void writePng(const std::string& path, const std::uint32_t* rgba8, int width, int height) {
  if (width <= 0 || height <= 0)
    throw Error(path + ": cannot write a " + std::to_string(width) + "x" + std::to_string(height) +
                " PNG");
  const std::filesystem::path target(path);
  // Same folder as the target, so the rename is atomic; hidden and not ending in .png, so a
  // glob for captures never picks it up.
  std::string tmp =
      (target.parent_path() / ("." + target.filename().string() + ".XXXXXX")).string();
  const int fd = mkstemp(tmp.data());
  if (fd < 0) throw Error(path + ": cannot create a temporary file: " + std::strerror(errno));
  fchmod(fd, 0644);  // mkstemp makes it 0600; captures are for other users too
  FILE* f = fdopen(fd, "wb");
  if (!f) {
    close(fd);
    unlink(tmp.c_str());
    throw Error(path + ": cannot open the temporary file: " + std::strerror(errno));
  }
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGBA;
  const int written = png_image_write_to_stdio(&image, f, 0, rgba8, 0, nullptr);
  const std::string message = image.message;
  png_image_free(&image);
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = !written ? message : std::strerror(errno);
    unlink(tmp.c_str());
    throw Error(path + ": cannot write the PNG: " + why);
  }
}

Image readPng(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str()))
    throw Error(path + ": cannot read the PNG: " + image.message);
  image.format = PNG_FORMAT_RGBA;
  Image out(static_cast<int>(image.width), static_cast<int>(image.height));
  if (!png_image_finish_read(&image, nullptr, out.pixels.data(), 0, nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    throw Error(path + ": cannot decode the PNG: " + message);
  }
  return out;
}

}  // namespace wall
