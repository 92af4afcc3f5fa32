#pragma once
// The controller page's routes on the control server (behind its checks, apps/ControlRequests.h):
// the page itself ("/" and its files, embedded by cmake/EmbedFiles.cmake), the latest whole-wall
// preview as PNG, and the layout the page draws the display outlines and names from.
//
//   GET /, /index.html, /app.js, /style.css
//   GET /api/preview.png   the assembled preview (bezels dark, outlines), canvas / factor
//   GET /api/layout        {"canvas": [w, h], "preview": {"size": [w, h], "factor": f},
//                           "displays": [{"name", "rect": [x0, y0, x1, y1], "process"}]}: the
//                          canvas now (a service wall may move or resize the window)
namespace app {

class ControlRequests;
class Preview;

// Before the server starts. `preview` must outlive the server.
void addPageRoutes(ControlRequests& server, const Preview& preview);
// The wall's own page (serve --control; its API: apps/WallControl.h): "/" and its files.
void addWallPageRoutes(ControlRequests& server);

}  // namespace app
