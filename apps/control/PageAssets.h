#pragma once
// The controller page's files (apps/control/page/) and the wall's (apps/control/wall/), compiled
// into the binary by cmake/EmbedFiles.cmake: the control server serves them with no file on disk
// and no CDN.
#include <string_view>
#include <vector>

namespace app {

struct PageAsset {
  std::string_view path;  // "/index.html", "/app.js", ...
  std::string_view contentType;
  std::string_view body;
};

const std::vector<PageAsset>& pageAssets();
// The wall's own page (serve --control: apps/WallControl.h), from apps/control/wall/.
const std::vector<PageAsset>& wallPageAssets();

// The asset served at `path` ("/" is "/index.html"), or nullptr.
inline const PageAsset* findPageAsset(std::string_view path) {
  if (path == "/") path = "/index.html";
  for (const PageAsset& a : pageAssets())
    if (a.path == path) return &a;
  return nullptr;
}

}  // namespace app
