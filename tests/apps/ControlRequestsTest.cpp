// The control API's checks one by one (apps/ControlRequests.h), and where its secret comes from
// (apps/ControlSecret.h); the attacks against a running job are control_attacks_test.py.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "apps/ControlRequests.h"
#include "apps/ControlSecret.h"

namespace app {
namespace {

const std::string kToken = "0123456789abcdef0123456789abcdef";

ControlRequests server() {
  ControlRequests r(ControlAccess{kToken, 8080, {"0.0.0.0", "wall.example"}});
  r.get("/api/status", [](const HttpRequest&) {
    return HttpReply{200, "application/json", "{}", {}};
  });
  r.post("/api/stop", [](const HttpRequest& q) {
    return HttpReply{
        200, "application/json", "{\"body\": " + std::to_string(q.body.size()) + "}", {}};
  });
  return r;
}

HttpRequest request(const std::string& method, const std::string& path, const std::string& host) {
  HttpRequest q;
  q.method = method;
  q.path = path;
  q.headers.emplace_back("Host", host);
  return q;
}

HttpRequest bearer(const std::string& method, const std::string& path, const std::string& host) {
  HttpRequest q = request(method, path, host);
  q.headers.emplace_back("authorization", "bearer " + kToken);  // any case
  return q;
}

TEST(ControlRequests, HostMustNameTheServer) {
  const ControlRequests r = server();
  for (const char* host : {"127.0.0.1:8080", "localhost:8080", "[::1]:8080", "127.0.0.2:9999",
                           "localhost:1234", "wall.example:8080", "WALL.example:8080"})
    EXPECT_EQ(r.handle(bearer("GET", "/api/status", host)).status, 200) << host;
  for (const char* host : {"evil.example:8080", "wall.example:8081", "wall.example",
                           "127.0.0.1.evil.example:8080", "localhost.:8080", "", ":8080",
                           "[::1:8080", "localhost:0", "localhost:99999", "localhost:"})
    EXPECT_EQ(r.handle(bearer("GET", "/api/status", host)).status, 403) << host;
  HttpRequest noHost;
  noHost.method = "GET";
  noHost.path = "/api/status";
  noHost.headers.emplace_back("Authorization", "Bearer " + kToken);
  EXPECT_EQ(r.handle(noHost).status, 403);
}

TEST(ControlRequests, TheTokenIsRequired) {
  const ControlRequests r = server();
  EXPECT_EQ(r.handle(request("GET", "/api/status", "localhost:8080")).status, 401);
  HttpRequest wrong = request("POST", "/api/stop", "localhost:8080");
  wrong.headers.emplace_back("Authorization", "Bearer " + kToken.substr(1) + "0");
  EXPECT_EQ(r.handle(wrong).status, 401);
  // A wrong header is not saved by a right cookie.
  wrong.headers.emplace_back("Cookie", r.cookieName() + "=" + kToken);
  EXPECT_EQ(r.handle(wrong).status, 401);
  HttpRequest inUrl = request("GET", "/api/status", "localhost:8080");
  inUrl.query.emplace_back("token", kToken);
  EXPECT_EQ(r.handle(inUrl).status, 401);
  // Unknown paths are not told apart from known ones without it.
  EXPECT_EQ(r.handle(request("GET", "/nothing", "localhost:8080")).status, 401);
}

TEST(ControlRequests, ThePageAddressSetsTheCookieAndRedirects) {
  const ControlRequests r = server();
  HttpRequest page = request("GET", "/", "localhost:8080");
  page.query.emplace_back("token", kToken);
  const HttpReply reply = r.handle(page);
  EXPECT_EQ(reply.status, 303);
  std::string location, cookie;
  for (const auto& [name, value] : reply.headers) {
    if (name == "Location") location = value;
    if (name == "Set-Cookie") cookie = value;
  }
  EXPECT_EQ(location, "/");
  EXPECT_EQ(cookie, "dfbwall-control-8080=" + kToken + "; Path=/; HttpOnly; SameSite=Strict");
  page.query[0].second = "0123456789abcdef0123456789abcdee";
  EXPECT_EQ(r.handle(page).status, 401);
  page.query[0].second = kToken;
  page.headers[0].second = "evil.example:8080";
  EXPECT_EQ(r.handle(page).status, 403);
}

TEST(ControlRequests, ChangesByCookieNeedJsonFromTheOwnOrigin) {
  const ControlRequests r = server();
  const auto post = [&](const std::string& type, const std::string& origin) {
    HttpRequest q = request("POST", "/api/stop", "127.0.0.1:8080");
    q.headers.emplace_back("Cookie", "other=1; " + r.cookieName() + "=" + kToken + "; x=y");
    if (!type.empty()) q.headers.emplace_back("Content-Type", type);
    if (!origin.empty()) q.headers.emplace_back("Origin", origin);
    q.body = "{}";
    return r.handle(q).status;
  };
  EXPECT_EQ(post("application/json", "http://127.0.0.1:8080"), 200);
  EXPECT_EQ(post("application/json; charset=utf-8", "http://127.0.0.1:8080"), 200);
  EXPECT_EQ(post("text/plain", "http://127.0.0.1:8080"), 403);
  EXPECT_EQ(post("", "http://127.0.0.1:8080"), 403);
  EXPECT_EQ(post("application/json", ""), 403);
  EXPECT_EQ(post("application/json", "null"), 403);
  EXPECT_EQ(post("application/json", "http://127.0.0.1:8081"), 403);
  EXPECT_EQ(post("application/json", "https://127.0.0.1:8080"), 403);
  // Reads by cookie need neither.
  HttpRequest read = request("GET", "/api/status", "127.0.0.1:8080");
  read.headers.emplace_back("Cookie", r.cookieName() + "=" + kToken);
  EXPECT_EQ(r.handle(read).status, 200);
  // A script's Bearer POST needs no body and no content type.
  EXPECT_EQ(r.handle(bearer("POST", "/api/stop", "127.0.0.1:8080")).status, 200);
}

TEST(ControlRequests, EveryReplyCarriesTheSecurityHeaders) {
  const ControlRequests r = server();
  for (const HttpRequest& q : {request("GET", "/api/status", "evil.example:8080"),
                               request("GET", "/api/status", "localhost:8080"),
                               bearer("GET", "/api/status", "localhost:8080"),
                               bearer("DELETE", "/api/status", "localhost:8080"),
                               bearer("GET", "/nothing", "localhost:8080")}) {
    const HttpReply reply = r.handle(q);
    std::map<std::string, std::string> headers(reply.headers.begin(), reply.headers.end());
    EXPECT_EQ(headers["X-Frame-Options"], "DENY") << q.method << " " << q.path;
    EXPECT_EQ(headers["X-Content-Type-Options"], "nosniff");
    EXPECT_EQ(headers["Cache-Control"], "no-store");
    EXPECT_EQ(headers["Referrer-Policy"], "no-referrer");
    EXPECT_NE(headers["Content-Security-Policy"].find("default-src 'self'"), std::string::npos);
  }
}

TEST(ControlRequests, RoutesAnswerWithTheRightStatus) {
  const ControlRequests r = server();
  EXPECT_EQ(r.handle(bearer("GET", "/nothing", "localhost:8080")).status, 404);
  EXPECT_EQ(r.handle(bearer("GET", "/api/stop", "localhost:8080")).status, 405);
  EXPECT_EQ(r.handle(bearer("PUT", "/api/stop", "localhost:8080")).status, 405);
  HttpRequest big = bearer("POST", "/api/stop", "localhost:8080");
  big.body.assign(kMaxControlBody + 1, ' ');
  EXPECT_EQ(r.handle(big).status, 413);
  // A message quoting bytes that are not UTF-8 is still a reply.
  EXPECT_EQ(r.handle(bearer("GET", "/api/status", "\xff\xfe:8080")).status, 403);
}

TEST(ControlSecret, FromAFileCreatedPrivateThenReadAgain) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "control-secret-test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "token").string();
  const ControlSecret created = controlSecret(file);
  struct stat info {};
  ASSERT_EQ(::stat(file.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  EXPECT_FALSE(created.generated);
  EXPECT_EQ(created.token.size(), 32u);
  EXPECT_EQ(controlSecret(file).token, created.token);
  ::chmod(file.c_str(), 0640);
  try {
    controlSecret(file);
    ADD_FAILURE() << "a token file others may read was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file + ": other users may read it (mode 0640)"),
              std::string::npos)
        << e.what();
  }
  ::chmod(file.c_str(), 0600);
  std::ofstream(file) << "short\n";
  EXPECT_THROW(controlSecret(file), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(ControlSecret, FromTheEnvironmentOrGenerated) {
  ::setenv(kControlTokenVariable, "from-the-environment-1", 1);
  EXPECT_EQ(controlSecret("").token, "from-the-environment-1");
  ::setenv(kControlTokenVariable, "has a space in it 1234", 1);
  EXPECT_THROW(controlSecret(""), std::runtime_error);
  ::unsetenv(kControlTokenVariable);
  const ControlSecret generated = controlSecret("");
  EXPECT_TRUE(generated.generated);
  EXPECT_EQ(generated.token.size(), 32u);
  EXPECT_NE(generated.token, controlSecret("").token);
  EXPECT_TRUE(sameSecret(kToken, kToken));
  EXPECT_FALSE(sameSecret(kToken, kToken.substr(1)));
}

}  // namespace
}  // namespace app
