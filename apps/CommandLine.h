#pragma once
// The dfbwall commands as CLI11 sees them: the render job (dfbwall itself), `serve`, `relay` and
// `show`,
// each with only the options it reads, in help groups. An option several commands take is added
// by one function, so its name, check and default cannot drift between them.
#include <CLI/CLI.hpp>

#include <string>

#include "apps/Options.h"

namespace app {

// Option values that need more than CLI11's checks (apps/Options.cpp reads them).
struct RawOptions {
  std::string size, memoryLimit, captureQuota, background;
};

struct CommandLine {
  // Binds every option to its field: the render job's, serve's and show's to `options`, relay's
  // to `relay`.
  CommandLine(Options& options, RelayCommand& relay, RawOptions& raw);

  CLI::App root;  // the render job
  CLI::App* serve = nullptr;
  CLI::App* relay = nullptr;
  CLI::App* show = nullptr;

  // The subcommand given, else the render job.
  const CLI::App& command() const;
  // "dfbwall" or "dfbwall serve": how messages and help name the command given.
  std::string commandName() const;
  // After parsing: an argument the command given does not take ("--scene is not an option of
  // serve; the render job takes it (see dfbwall serve --help)"); empty when there is none.
  std::string misplacedArgument() const;
};

}  // namespace app
