#pragma once
// The control API's secret (docs/security.md, "The control API"): always one, loopback included,
// and never on the command line. From --control-token-file FILE (created 0600 with a fresh token
// when absent), else from the environment (DFBWALL_CONTROL_TOKEN), else generated for this run
// and printed once as the address to open.
#include <string>

namespace app {

constexpr const char* kControlTokenVariable = "DFBWALL_CONTROL_TOKEN";

struct ControlSecret {
  std::string token;
  bool generated = false;  // for this run only: the printed address is the only copy
  std::string source;      // where it came from, for the start line ("FILE", the variable)
};

// Throws std::runtime_error naming the file or the variable when the token there is unusable
// (too short, characters a cookie cannot carry, a file others may read).
ControlSecret controlSecret(const std::string& tokenFile);

// 32 hex digits from the kernel's random pool.
std::string generateToken();

// Compares in time independent of where they differ.
bool sameSecret(const std::string& a, const std::string& b);

}  // namespace app
