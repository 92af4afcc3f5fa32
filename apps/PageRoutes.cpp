#include "apps/PageRoutes.h"

#include <nlohmann/json.hpp>

#include "apps/ControlRequests.h"
#include "apps/Job.h"
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

void addPageRoutes(ControlRequests& server, const Job& job, const Preview& preview) {
  addAssets(server, pageAssets());
  server.get("/api/preview.png", [&preview](const HttpRequest&) {
    return HttpReply{200, "image/png", *preview.png().bytes, {}};
  });

  nlohmann::json layout;
  layout["canvas"] = {job.canvasWidth, job.canvasHeight};
  const wall::PreviewGrid& grid = preview.assembler()->grid();
  layout["preview"] = {{"size", {grid.width(), grid.height()}}, {"factor", grid.factor}};
  layout["displays"] = nlohmann::json::array();
  if (job.layout)
    for (const wall::Display& d : job.layout->displays)
      layout["displays"].push_back({{"name", d.name},
                                    {"rect", {d.rect.x0, d.rect.y0, d.rect.x1, d.rect.y1}},
                                    {"process", d.process}});
  server.get("/api/layout", [body = layout.dump()](const HttpRequest&) {
    return HttpReply{200, "application/json", body, {}};
  });
}

}  // namespace app
