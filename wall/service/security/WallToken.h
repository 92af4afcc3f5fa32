#pragma once
// Where the wall service's token comes from (docs/security.md, "The wall service"). Every process
// of a wall, every job, relay and in-situ program presents the same token at the ZeroMQ handshake
// (wall/service/security/Credentials.h). It is read from, in this order: `--token T` (for tests:
// visible in ps), `--token-file FILE`, the environment variable DFBWALL_TOKEN, and the default
// file defaultTokenFile(). `serve` creates a token file that is absent (mode 0600, a fresh random
// token, atomically: processes that start at once agree on one token); the others only read it.
#include <cstddef>
#include <string>

namespace wall::service {

constexpr const char* kTokenVariable = "DFBWALL_TOKEN";
constexpr std::size_t kMaxTokenBytes = 255;

// ${XDG_STATE_HOME:-$HOME/.local/state}/dfbwall/wall-token: private to the user, the same for a
// wall and the jobs one user starts on a host (or on hosts sharing a home directory).
std::string defaultTokenFile();

struct WallToken {
  std::string token;
  // Where it came from, for messages (never the token): "--token", "--token-file FILE",
  // "DFBWALL_TOKEN", or the default file's name.
  std::string source;
};

// The token from `given` (--token), `file` (--token-file), the environment or the default file.
// `create`: a token file that does not exist is created with a new token (serve). Throws
// base::Error naming the option or file: both --token and --token-file, an empty or unreadable
// file, a file other users may read, no token anywhere (the message says how to get one).
WallToken chooseWallToken(const std::string& given, const std::string& file, bool create);

// A new token: 32 random bytes as 64 hexadecimal digits.
std::string randomWallToken();

}  // namespace wall::service
