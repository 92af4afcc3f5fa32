#include "apps/PageRoutes.h"

#include <nlohmann/json.hpp>

#include "apps/ControlRequests.h"
#include "apps/Preview.h"
#include "apps/control/PageAssets.h"

namespace app {

namespace {

void addAssets(ControlRequests& server, const std::vector<PageAsset>& assets) {
  for (const PageAsset& asset : assets) {
    auto serve = [&asset](const HttpRequest&) {
      return HttpReply{200, std::string(asset.contentType), std::string(asset.body), {}};
    };
    server.get(std::string(asset.path), serve);
    if (asset.path == "/index.html") server.get("/", serve);
  }
}

}  // namespace

void addWallPageRoutes(ControlRequests& server) { addAssets(server, wallPageAssets()); }

void addPageRoutes(ControlRequests& server, const Preview& preview) {
  addAssets(server, pageAssets());
  server.get("/api/preview.png", [&preview](const HttpRequest&) {
    return HttpReply{200, "image/png", *preview.png().bytes, {}};
  });

  // The canvas the preview shows now: a service wall may move or resize the job's window.
  server.get("/api/layout", [&preview](const HttpRequest&) {
    const Preview::Canvas canvas = preview.canvas();
    nlohmann::json layout;
    layout["canvas"] = {canvas.grid.canvasWidth, canvas.grid.canvasHeight};
    layout["preview"] = {{"size", {canvas.grid.width(), canvas.grid.height()}},
                         {"factor", canvas.grid.factor}};
    layout["displays"] = nlohmann::json::array();
    if (canvas.layout)
      for (const wall::Display& d : canvas.layout->displays)
        layout["displays"].push_back({{"name", d.name},
                                      {"rect", {d.rect.x0, d.rect.y0, d.rect.x1, d.rect.y1}},
                                      {"process", d.process}});
    return HttpReply{200, "application/json", layout.dump(), {}};
  });
}

}  // namespace app
