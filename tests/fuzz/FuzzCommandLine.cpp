// libFuzzer target: the command line. Arguments are the input split at NUL bytes; every parse
// ends in an exit code or "go on", never a crash.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "apps/Options.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> args{"dfbwall"};
  std::string current;
  for (std::size_t i = 0; i < size; ++i) {
    if (data[i] == 0) {
      args.push_back(current);
      current.clear();
    } else {
      current += static_cast<char>(data[i]);
    }
  }
  args.push_back(current);
  if (args.size() > 64) return 0;
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  app::Options options;
  (void)app::parseOptions(static_cast<int>(args.size()), argv.data(), options, false);
  return 0;
}
