#include "apps/ControlSecret.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace app {
namespace {

// Why `token` cannot be the secret, or empty. It travels in a cookie and an Authorization
// header: letters, digits and -._~+/= only.
std::string tokenProblem(const std::string& token) {
  if (token.size() < 16) return "the token is shorter than 16 characters";
  if (token.size() > 256) return "the token is longer than 256 characters";
  for (const char c : token)
    if (!std::isalnum(static_cast<unsigned char>(c)) && !std::strchr("-._~+/=", c))
      return "the token may hold only letters, digits and -._~+/=";
  return {};
}

std::string readTokenFile(const std::string& file) {
  struct stat info {};
  if (::stat(file.c_str(), &info) != 0)
    throw std::runtime_error("--control-token-file " + file + ": " + std::strerror(errno));
  if ((info.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(info.st_mode & 07777));
    throw std::runtime_error("--control-token-file " + file + ": other users may read it (mode " +
                             mode + "); chmod 600 " + file);
  }
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error("--control-token-file " + file + ": cannot read it");
  std::string token = text.str();
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  if (const std::string problem = tokenProblem(token); !problem.empty())
    throw std::runtime_error("--control-token-file " + file + ": " + problem);
  return token;
}

// A fresh token in a new file only its owner may read; false when the file exists already.
bool createTokenFile(const std::string& file, const std::string& token) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw std::runtime_error("--control-token-file " + file +
                             ": cannot create it: " + std::strerror(errno));
  }
  const std::string line = token + "\n";
  const bool written = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size());
  ::close(fd);
  if (!written) {
    ::unlink(file.c_str());
    throw std::runtime_error("--control-token-file " + file + ": cannot write it");
  }
  return true;
}

}  // namespace

std::string generateToken() {
  std::ifstream random("/dev/urandom", std::ios::binary);
  unsigned char bytes[16];
  if (!random.read(reinterpret_cast<char*>(bytes), sizeof bytes))
    throw std::runtime_error("--control: cannot read /dev/urandom for a token");
  static const char* hex = "0123456789abcdef";
  std::string token;
  for (unsigned char b : bytes) token += {hex[b >> 4], hex[b & 15]};
  return token;
}

bool sameSecret(const std::string& a, const std::string& b) {
  // The length of a token is no secret; its characters are.
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(static_cast<unsigned char>(a[i]) ^
                                       static_cast<unsigned char>(b[i]));
  return diff == 0;
}

ControlSecret controlSecret(const std::string& tokenFile) {
  if (!tokenFile.empty()) {
    const std::string fresh = generateToken();
    if (createTokenFile(tokenFile, fresh)) return {fresh, false, tokenFile};
    return {readTokenFile(tokenFile), false, tokenFile};
  }
  if (const char* value = std::getenv(kControlTokenVariable)) {
    std::string token = value;
    if (const std::string problem = tokenProblem(token); !problem.empty())
      throw std::runtime_error(std::string(kControlTokenVariable) + ": " + problem);
    return {token, false, kControlTokenVariable};
  }
  return {generateToken(), true, {}};
}

}  // namespace app
