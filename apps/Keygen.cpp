// `dfbwall keygen DIR`: a CURVE key pair for `serve --curve DIR` (docs/security.md, "The wall
// service"; wall/service/security/Credentials.h). No MPI: it runs wherever the keys are made.
// One positional argument and --help: no option parser needed.
#include <cstdio>
#include <string>

#include "apps/Run.h"
#include "wall/service/security/Credentials.h"

namespace app {

int runKeygen(int argc, char** argv) {
  const char* usage =
      "usage: dfbwall keygen DIR\n"
      "writes a CURVE key pair for the wall service into DIR (created; existing keys are never\n"
      "replaced): DIR/wall-public.key, for jobs, relays and joining processes (--server-key\n"
      "FILE), and DIR/wall-secret.key (mode 0600), for the wall's hosts only (serve --curve DIR)\n";
  const std::string first = argc > 1 ? argv[1] : "";
  if (argc == 2 && (first == "-h" || first == "--help")) {
    std::fputs(usage, stdout);
    return 0;
  }
  if (argc != 2 || first.empty() || first[0] == '-') {
    std::fprintf(
        stderr, "dfbwall keygen: error: %s\n%s",
        argc < 2 ? "it needs DIR, the folder for the key pair" : "it takes one argument, DIR",
        usage);
    return 2;
  }
  try {
    const std::string publicKey = wall::service::writeKeyPair(first);
    std::printf(
        "dfbwall keygen: wrote %s and its secret key; serve --curve %s, clients "
        "--server-key %s\n",
        publicKey.c_str(), first.c_str(), publicKey.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall keygen: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace app
