#pragma once
// PNG files of RGBA8 images (libpng). Writing goes to a temporary file in the same folder and is
// renamed into place, so a reader never sees half a file. Both throw base::Error naming the
// file on failure. Safe to call from several threads on different files.
#include <cstdint>
#include <cstdio>
#include <string>

#include "wall/image/Image.h"

namespace wall {

void writePng(const std::string& path, const std::uint32_t* rgba8, int width, int height);
inline void writePng(const std::string& path, const Image& image) {
  writePng(path, image.pixels.data(), image.width, image.height);
}
// The PNG into an open stream (a base::AtomicFile's, which the caller commits); `path` names it
// in messages.
void writePngTo(std::FILE* stream, const std::string& path, const std::uint32_t* rgba8, int width,
                int height);

// The PNG file's bytes in memory (for a server to send), or throws base::Error.
std::string encodePng(const Image& image);

// Any PNG, converted to RGBA8.
Image readPng(const std::string& path);

}  // namespace wall
