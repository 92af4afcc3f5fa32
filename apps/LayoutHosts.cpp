// dfbwall-layout LAYOUT: a wall layout as scripts see it, without MPI. Prints
//   canvas WIDTHxHEIGHT
//   processes W
//   process P host HOST displays NAME[,NAME...]      (one line per wall process; HOST "-": none)
// scripts/cluster places each wall process on the host its displays name. A bad layout prints
// every problem (file, line, field) and exits 1; displays of one process naming different hosts
// are a problem here too, since one process runs on one host.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "wall/layout/Layout.h"

int main(int argc, char** argv) {
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: %s LAYOUT.toml\n", argv[0]);
    return 2;
  }
  try {
    const wall::Layout layout = wall::loadLayout(argv[1]);
    std::vector<std::string> hosts(static_cast<size_t>(layout.processCount));
    std::vector<std::string> names(static_cast<size_t>(layout.processCount));
    for (const wall::Display& d : layout.displays) {
      std::string& host = hosts[static_cast<size_t>(d.process)];
      std::string& list = names[static_cast<size_t>(d.process)];
      if (!list.empty() && host != d.host) {
        std::fprintf(stderr,
                     "%s:%d: display '%s': field 'host': \"%s\", but wall process %d also drives "
                     "a display on \"%s\" (one process runs on one host)\n",
                     layout.file.c_str(), d.lines.table, d.name.c_str(), d.host.c_str(), d.process,
                     host.c_str());
        return 1;
      }
      host = d.host;
      list += (list.empty() ? "" : ",") + d.name;
    }
    std::printf("canvas %dx%d\nprocesses %d\n", layout.canvasWidth, layout.canvasHeight,
                layout.processCount);
    for (int p = 0; p < layout.processCount; ++p)
      std::printf(
          "process %d host %s displays %s\n", p,
          hosts[static_cast<size_t>(p)].empty() ? "-" : hosts[static_cast<size_t>(p)].c_str(),
          names[static_cast<size_t>(p)].c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall-layout: %s\n", e.what());
    return 1;
  }
}
