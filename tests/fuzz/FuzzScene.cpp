// libFuzzer target: scene TOML text, read through a file as the app does. Problems are
// base::Error (or another std::exception with a message), never a crash.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "renderers/SceneToml.h"
#include "renderers/scivis/Registration.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  renderers::scivis::registerSciVis();  // the scivis parts of scenes, as dfbwall reads them
  // Mesh paths in the text are read relative to the scene's folder: an empty private one.
  static const std::string folder = [] {
    char pattern[] = "/tmp/dfbwall-fuzz-scene.XXXXXX";
    return std::string(mkdtemp(pattern));
  }();
  const std::string path = folder + "/scene.toml";
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
    (void)renderers::readSceneToml(path);
  } catch (const std::exception&) {
  }
  return 0;
}
