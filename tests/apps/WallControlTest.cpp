// The wall's window manager routes (apps/WallControl.h) behind the control server's checks: what
// each request is answered and what it asks of the wall. The wall here is a list the test holds;
// the routes on a real service wall are service_window_manager (wall_manager_test.py).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "apps/ControlRequests.h"
#include "apps/WallControl.h"
#include "wall/image/Png.h"
#include "wall/layout/Layout.h"

namespace app {
namespace {

using Window = wall::service::JobDesk::Window;
using State = wall::service::JobDesk::State;
const std::string kToken = "0123456789abcdef0123456789abcdef";

constexpr const char* k2x1 = R"(
[[display]]
name = "left"
origin = [0, 0]
size = [200, 150]
process = 0
[[display]]
name = "right"
origin = [210, 0]
size = [200, 150]
process = 1
)";

wall::Layout twoByOne() {
  wall::LayoutResult result = wall::readLayoutText(k2x1, "2x1.toml");
  EXPECT_TRUE(result.ok());
  return result.layout;
}

class WallControlTest : public ::testing::Test {
 protected:
  WallControlTest() : layout(twoByOne()), requests(ControlAccess{kToken, 8080, {"127.0.0.1"}}) {
    Window a;
    a.number = 1;
    a.host = "render1";
    a.job = "scivis builtin:wavelet";
    a.page = "http://render1:8081/";
    a.rect = {0, 0, 300, 150};
    a.z = 0;
    a.state = State::Running;
    a.frames = 40;
    a.fps = 19.96;
    Window b = a;
    b.number = 12;
    b.page.clear();
    b.rect = {100, 20, 400, 120};
    b.z = 1;
    b.idle = true;
    list = {a, b};
    WallWindows windows;
    windows.list = [this] { return list; };
    windows.raise = [this](std::uint64_t n) {
      raised.push_back(n);
      return n != 12 || !goneBeforeRaise;
    };
    windows.close = [this](std::uint64_t n, const std::string& why) {
      closed.emplace_back(n, why);
      return true;
    };
    windows.move = [this](std::uint64_t n, const dfb::Region& rect, int& code) {
      moved.emplace_back(n, rect);
      code = moveCode;
      return code == 200 ? std::string() : std::string("the window is moving already");
    };
    addWallRoutes(requests, WallFacts{&layout, 0xff302010u, 3}, std::move(windows));
  }

  HttpReply send(const std::string& method, const std::string& path, const std::string& body = {}) {
    HttpRequest q;
    q.method = method;
    q.path = path;
    q.body = body;
    q.headers = {{"Host", "127.0.0.1:8080"}, {"Authorization", "Bearer " + kToken}};
    return requests.handle(q);
  }
  static nlohmann::json json(const HttpReply& r) { return nlohmann::json::parse(r.body); }

  wall::Layout layout;
  ControlRequests requests;
  std::vector<Window> list;
  std::vector<std::uint64_t> raised;
  std::vector<std::pair<std::uint64_t, std::string>> closed;
  std::vector<std::pair<std::uint64_t, dfb::Region>> moved;
  int moveCode = 200;
  bool goneBeforeRaise = false;
};

TEST_F(WallControlTest, TheWallAndItsWindowsAreDescribed) {
  const HttpReply wall = send("GET", "/api/wall");
  ASSERT_EQ(wall.status, 200);
  EXPECT_EQ(json(wall), nlohmann::json::parse(R"({
    "canvas": {"w": 410, "h": 150},
    "displays": [{"name": "left", "rect": {"x": 0, "y": 0, "w": 200, "h": 150}, "process": 0},
                 {"name": "right", "rect": {"x": 210, "y": 0, "w": 200, "h": 150}, "process": 1}],
    "background": "#102030", "max_jobs": 3})"));
  const HttpReply windows = send("GET", "/api/windows");
  ASSERT_EQ(windows.status, 200);
  EXPECT_EQ(json(windows), nlohmann::json::parse(R"([
    {"id": "1", "job": "scivis builtin:wavelet", "host": "render1",
     "rect": {"x": 0, "y": 0, "w": 300, "h": 150}, "z": 0, "fps": 20.0, "state": "running",
     "frames": 40, "page": "http://render1:8081/"},
    {"id": "12", "job": "scivis builtin:wavelet", "host": "render1",
     "rect": {"x": 100, "y": 20, "w": 300, "h": 100}, "z": 1, "fps": 20.0, "state": "idle",
     "frames": 40, "page": null}])"));
  list[1].state = State::Starting;
  EXPECT_EQ(json(send("GET", "/api/windows"))[1]["state"], "starting");
  list[1].state = State::Ending;
  EXPECT_EQ(json(send("GET", "/api/windows"))[1]["state"], "ending");
  list.clear();
  EXPECT_EQ(send("GET", "/api/windows").body, "[]");
}

TEST_F(WallControlTest, RaiseAndCloseReachTheWall) {
  const HttpReply raise = send("POST", "/api/windows/12", R"({"raise": true})");
  EXPECT_EQ(raise.status, 200);
  EXPECT_EQ(json(raise), nlohmann::json::parse(R"({"id": "12", "raised": true})"));
  EXPECT_EQ(raised, (std::vector<std::uint64_t>{12}));
  const HttpReply close = send("DELETE", "/api/windows/1");
  EXPECT_EQ(close.status, 200);
  EXPECT_EQ(json(close), nlohmann::json::parse(R"({"id": "1", "closed": true})"));
  ASSERT_EQ(closed.size(), 1u);
  EXPECT_EQ(closed[0].first, 1u);
  EXPECT_EQ(closed[0].second, "closed from the wall's control page");
  // A window that leaves between the look-up and the raise.
  goneBeforeRaise = true;
  EXPECT_EQ(send("POST", "/api/windows/12", R"({"raise": true})").status, 404);
}

TEST_F(WallControlTest, MovesAndResizesKeepTheFieldsNotGivenAndReachTheWall) {
  // Window 12 is 100,20,300,100 on a 410x150 canvas.
  const HttpReply all = send("POST", "/api/windows/12", R"({"x": 1, "y": 2, "w": 30, "h": 40})");
  EXPECT_EQ(all.status, 200);
  EXPECT_EQ(json(all),
            nlohmann::json::parse(R"({"id": "12", "rect": {"x": 1, "y": 2, "w": 30, "h": 40}})"));
  EXPECT_EQ(send("POST", "/api/windows/12", R"({"x": 0})").status, 200);
  EXPECT_EQ(send("POST", "/api/windows/12", R"({"w": 310, "h": 130})").status, 200);
  EXPECT_EQ(send("POST", "/api/windows/1", R"({"fullscreen": true})").status, 200);
  const std::vector<std::pair<std::uint64_t, dfb::Region>> expected = {{12, {1, 2, 31, 42}},
                                                                       {12, {0, 20, 300, 120}},
                                                                       {12, {100, 20, 410, 150}},
                                                                       {1, {0, 0, 410, 150}}};
  ASSERT_EQ(moved.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(moved[i].first, expected[i].first) << i;
    EXPECT_EQ(moved[i].second, expected[i].second) << i;
  }
}

TEST_F(WallControlTest, TheWallsRefusalOfAMoveIsPassedOnWithItsCode) {
  for (const int code : {400, 404, 409}) {
    moveCode = code;
    const HttpReply r = send("POST", "/api/windows/1", R"({"x": 10})");
    EXPECT_EQ(r.status, code);
    EXPECT_EQ(json(r)["error"], "window 1: the window is moving already");
  }
}

TEST_F(WallControlTest, BadBodiesAndUnknownWindowsAreRefusedAndNothingIsDone) {
  for (const char* body : {"",
                           "raise",
                           "[]",
                           "{}",
                           "null",
                           R"({"raise": false})",
                           R"({"raise": 1})",
                           R"({"raise": true, "colour": "red"})",
                           R"({"raise": true, "x": 5})",
                           R"({"fullscreen": false})",
                           R"({"fullscreen": 1})",
                           R"({"fullscreen": true, "x": 0})",
                           R"({"x": 1.5})",
                           R"({"x": "1"})",
                           R"({"x": null})",
                           R"({"w": 0})",
                           R"({"h": -3})",
                           R"({"x": -1})",
                           R"({"y": 51})",
                           R"({"x": 111})",
                           R"({"x": 4294967296})",
                           R"({"w": 18446744073709551615})",
                           R"({"x": 2147483647, "w": 2147483647})",
                           R"({"x": 1, "size": 3})"}) {
    const HttpReply r = send("POST", "/api/windows/12", body);
    EXPECT_EQ(r.status, 400) << body;
    EXPECT_TRUE(json(r).contains("error")) << body;
  }
  EXPECT_EQ(json(send("POST", "/api/windows/12", R"({"x": 111})"))["error"],
            "window 111,20,300,100 is not inside the wall's canvas (410x150)");
  EXPECT_EQ(json(send("POST", "/api/windows/12", R"({"w": 0})"))["error"],
            "window 100,20,0,100: w and h must be positive");
  EXPECT_EQ(json(send("POST", "/api/windows/12", R"({"x": 1.5})"))["error"],
            "x must be an integer (canvas pixels), not 1.5");
  for (const char* path :
       {"/api/windows/2", "/api/windows/01", "/api/windows/+1", "/api/windows/1x",
        "/api/windows/18446744073709551616", "/api/windows/%31"}) {
    EXPECT_EQ(send("POST", path, R"({"raise": true})").status, 404) << path;
    EXPECT_EQ(send("DELETE", path).status, 404) << path;
  }
  // Routes are one segment deep; other methods are told which serve them.
  EXPECT_EQ(send("POST", "/api/windows/", R"({"raise": true})").status, 404);
  EXPECT_EQ(send("POST", "/api/windows/1/x", R"({"raise": true})").status, 404);
  EXPECT_EQ(send("DELETE", "/api/windows").status, 405);
  const HttpReply put = send("PUT", "/api/windows/1", "{}");
  EXPECT_EQ(put.status, 405);
  EXPECT_TRUE(raised.empty());
  EXPECT_TRUE(closed.empty());
  EXPECT_TRUE(moved.empty());
  EXPECT_EQ(send("POST", "/api/windows/2", R"({"x": 1})").status, 404);
  EXPECT_TRUE(moved.empty());
}

TEST_F(WallControlTest, AThumbnailIsItsWindowsPngOrSaysWhyNot) {
  // Before the wall made one: 503, saying so.
  HttpReply r = send("GET", "/api/windows/1/thumbnail");
  EXPECT_EQ(r.status, 503);
  EXPECT_NE(r.body.find("no thumbnail yet"), std::string::npos) << r.body;
  auto image = std::make_shared<wall::Image>(3, 2, wall::rgba8(9, 8, 7));
  image->at(2, 1) = 0;  // a cell on the bezels only: transparent
  list[0].thumbnail = image;
  r = send("GET", "/api/windows/1/thumbnail");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.contentType, "image/png");
  EXPECT_EQ(r.body, wall::encodePng(*image));
  // Unknown windows, ids that are no number, other methods.
  for (const char* path : {"/api/windows/3/thumbnail", "/api/windows/x/thumbnail",
                           "/api/windows/01/thumbnail", "/api/windows//thumbnail"})
    EXPECT_EQ(send("GET", path).status, 404) << path;
  EXPECT_EQ(send("POST", "/api/windows/1/thumbnail", "{}").status, 405);
  EXPECT_EQ(send("GET", "/api/windows/1/other").status, 404);
}

TEST_F(WallControlTest, EveryRouteIsBehindTheServersChecks) {
  for (const auto& [method, path] :
       std::vector<std::pair<std::string, std::string>>{{"GET", "/api/wall"},
                                                        {"GET", "/api/windows"},
                                                        {"POST", "/api/windows/1"},
                                                        {"DELETE", "/api/windows/1"}}) {
    HttpRequest q;
    q.method = method;
    q.path = path;
    q.body = R"({"raise": true})";
    q.headers = {{"Host", "127.0.0.1:8080"}};
    EXPECT_EQ(requests.handle(q).status, 401) << method << " " << path;
    q.headers = {{"Host", "evil.example:8080"}, {"Authorization", "Bearer " + kToken}};
    EXPECT_EQ(requests.handle(q).status, 403) << method << " " << path;
  }
  EXPECT_EQ(send("POST", "/api/windows/1", std::string(kMaxControlBody + 1, ' ')).status, 413);
  EXPECT_TRUE(raised.empty());
  EXPECT_TRUE(closed.empty());
  EXPECT_TRUE(moved.empty());
}

TEST(WindowNumber, OnlyPlainDecimalNumbers) {
  EXPECT_EQ(windowNumber("1"), 1u);
  EXPECT_EQ(windowNumber("18446744073709551615"), 18446744073709551615u);
  for (const char* id : {"", "0", "01", "-1", "+1", " 1", "1 ", "1e3", "0x10",
                         "18446744073709551616", "999999999999999999999"})
    EXPECT_FALSE(windowNumber(id).has_value()) << id;
}

}  // namespace
}  // namespace app
