#include "wall/service/security/WallToken.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "base/Error.h"

namespace wall::service {
namespace {

std::string trimmed(std::string s) {
  while (!s.empty() &&
         (s.back() == '\n' || s.back() == '\r' || s.back() == ' ' || s.back() == '\t'))
    s.pop_back();
  return s;
}

std::string readToken(const std::string& path, const std::string& what) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0)
    throw base::Error(what + ": cannot read it (" + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode)) throw base::Error(what + ": not a regular file");
  // A secret others can read is no secret: refuse it, as ssh does its keys.
  if ((st.st_mode & 077) != 0)
    throw base::Error(what + ": other users may read it; make it private (chmod 600 " + path + ")");
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) throw base::Error(what + ": empty or unreadable");
  line = trimmed(line);
  if (line.empty()) throw base::Error(what + ": the first line (the token) is empty");
  return line;
}

// Writes a new token to `path` unless it exists: a private temporary file linked to its name
// (link fails when the name exists), so a reader never sees half a token and processes that
// start at once all read the one that won.
void createToken(const std::string& path) {
  const std::filesystem::path target(path);
  if (target.has_parent_path() && !std::filesystem::exists(target.parent_path())) {
    std::error_code error;
    std::filesystem::create_directories(target.parent_path(), error);
    if (error) throw base::Error(path + ": cannot create its folder (" + error.message() + ")");
    std::filesystem::permissions(target.parent_path(), std::filesystem::perms::owner_all, error);
  }
  std::string temporary = path + ".XXXXXX";
  const int fd = mkstemp(temporary.data());  // mode 0600
  if (fd < 0) throw base::Error(path + ": cannot create it (" + std::strerror(errno) + ")");
  const std::string text = randomWallToken() + "\n";
  const bool written = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const bool synced = fsync(fd) == 0;
  close(fd);
  const int linked = written && synced ? link(temporary.c_str(), path.c_str()) : -1;
  const int linkError = errno;
  unlink(temporary.c_str());
  if (!written || !synced) throw base::Error(path + ": cannot write it");
  if (linked != 0 && linkError != EEXIST)
    throw base::Error(path + ": cannot create it (" + std::strerror(linkError) + ")");
}

// PLAIN carries the password with a one-byte length.
WallToken checked(WallToken t) {
  if (t.token.size() > kMaxTokenBytes)
    throw base::Error(t.source + ": a token of " + std::to_string(t.token.size()) +
                      " characters; at most " + std::to_string(kMaxTokenBytes));
  return t;
}

WallToken choose(const std::string& given, const std::string& file, bool create) {
  if (!given.empty() && !file.empty())
    throw base::Error("--token and --token-file: give one of them");
  if (!given.empty()) return {given, "--token"};
  if (!file.empty()) {
    if (create && !std::filesystem::exists(file)) createToken(file);
    return {readToken(file, "--token-file " + file), "--token-file " + file};
  }
  if (const char* env = std::getenv(kTokenVariable); env && *env)
    return {trimmed(env), kTokenVariable};
  const std::string fallback = defaultTokenFile();
  if (create && !std::filesystem::exists(fallback)) createToken(fallback);
  if (!std::filesystem::exists(fallback))
    throw base::Error("no wall token: give --token-file FILE (the wall's) or " +
                      std::string(kTokenVariable) + "; without either, the token is read from " +
                      fallback + ", which `dfbwall serve` creates on this host");
  return {readToken(fallback, "the wall token file " + fallback), fallback};
}

}  // namespace

std::string defaultTokenFile() {
  const char* state = std::getenv("XDG_STATE_HOME");
  if (state && *state == '/') return std::string(state) + "/dfbwall/wall-token";
  const char* home = std::getenv("HOME");
  if (!home || !*home)
    throw base::Error("no wall token: HOME is not set; give --token-file FILE or " +
                      std::string(kTokenVariable));
  return std::string(home) + "/.local/state/dfbwall/wall-token";
}

std::string randomWallToken() {
  if (sodium_init() < 0) throw base::Error("libsodium failed to start");
  unsigned char bytes[32];
  randombytes_buf(bytes, sizeof bytes);
  char hex[2 * sizeof bytes + 1];
  sodium_bin2hex(hex, sizeof hex, bytes, sizeof bytes);
  return hex;
}

WallToken chooseWallToken(const std::string& given, const std::string& file, bool create) {
  return checked(choose(given, file, create));
}

}  // namespace wall::service
