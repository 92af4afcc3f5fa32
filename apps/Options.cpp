#include "apps/Options.h"

#include <CLI/CLI.hpp>

#include "apps/CommandLine.h"
#include "base/MemoryBudget.h"
#include "renderers/picture/PictureRenderer.h"
#include "renderers/picture/PictureSequence.h"
#include "wall/layout/Window.h"
#include "wall/service/protocol/Codec.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace app {
namespace {

// "WxH" with positive integers, e.g. 1920x1080.
std::string parseSize(const std::string& text, int& width, int& height) {
  const char* const usage = "--size must look like WIDTHxHEIGHT, e.g. 512x512";
  const size_t x = text.find('x');
  if (x == std::string::npos || x == 0 || x + 1 == text.size()) return usage;
  const char* end = text.data() + text.size();
  auto [afterWidth, e1] = std::from_chars(text.data(), text.data() + x, width);
  auto [afterHeight, e2] = std::from_chars(text.data() + x + 1, end, height);
  if (e1 != std::errc() || e2 != std::errc() || afterWidth != text.data() + x || afterHeight != end)
    return usage;
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    return "--size: width and height must be between 1 and 65536";
  return {};
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The render job's renderer, data and outputs. Empty when fine.
std::string renderingProblem(const Options& o, bool ghostGiven) {
  if (o.bricks > 0 && o.renderer != "scivis")
    return "--bricks distributes the scivis renderer's data: add --renderer scivis";
  if (ghostGiven && o.bricks == 0)
    return "--ghost chooses the ghost data of bricks: add --bricks N";
  if (o.bricks > 0 && o.distribution == "dynamic")
    return "--bricks: tiles are planned by brick; --distribution dynamic does not apply";
  if (o.renderer == "pattern" && o.distribution == "dynamic")
    return "--distribution dynamic balances noisy tiles by averaging redundant inputs; the "
           "pattern renderer draws a new picture every frame: use static or roundrobin";
  if (!o.previewFile.empty() && !endsWith(o.previewFile, ".png"))
    return "--preview " + o.previewFile + ": the name must end in .png";
  if (!o.image.empty() && !endsWith(o.image, ".png") && !endsWith(o.image, ".pfm"))
    return "--image " + o.image + ": the name must end in .png (RGBA8) or .pfm (linear float)";
  // CLI11's range checks let NaN through (every comparison with it is false).
  if (!std::isfinite(o.exposure) || !std::isfinite(o.orbit))
    return "--exposure and --orbit must be finite numbers";
  if (!o.image.empty()) {
    // The image reaches rank 0 in one MPI gather, whose counts are ints.
    const std::uint64_t bytes =
        std::uint64_t(o.width) * std::uint64_t(o.height) * (endsWith(o.image, ".pfm") ? 16u : 4u);
    if (bytes > std::uint64_t(std::numeric_limits<int>::max()))
      return "--image " + o.image + ": a " + std::to_string(o.width) + "x" +
             std::to_string(o.height) + " image is " + std::to_string(bytes) +
             " bytes; one gather carries at most 2^31-1 (use a smaller --size, or .png)";
  }
  return {};
}

// Parses `args` (args[0]: the program) into `cli`'s fields. -1: go on; else the exit code (0 after
// --help, 2 after a message when `print`).
int parseArguments(CommandLine& cli, std::vector<std::string> args, bool print) {
  try {
    std::reverse(args.begin(), args.end());  // CLI11 takes them last first
    args.pop_back();                         // the program
    cli.root.parse(args);
  } catch (const CLI::CallForHelp& e) {
    return print ? cli.root.exit(e) : 0;
  } catch (const CLI::ParseError& e) {
    if (print)
      std::fprintf(stderr, "%s: error: %s (see %s --help)\n", cli.commandName().c_str(), e.what(),
                   cli.commandName().c_str());
    return 2;
  }
  if (const std::string problem = cli.misplacedArgument(); !problem.empty()) {
    if (print) std::fprintf(stderr, "%s: error: %s\n", cli.commandName().c_str(), problem.c_str());
    return 2;
  }
  return -1;
}

// "#rrggbb" into RGBA8 with R in the low byte (wall/image/Image.h). Empty when fine.
std::string parseBackground(const std::string& b, std::uint32_t& rgba) {
  std::uint32_t rgb = 0;
  const bool hex = b.size() == 7 && b[0] == '#' &&
                   std::from_chars(b.data() + 1, b.data() + 7, rgb, 16).ptr == b.data() + 7;
  if (!hex) return "--background must be #rrggbb (e.g. #000000), not '" + b + "'";
  rgba = 0xff000000u | (rgb >> 16) | (rgb & 0xff00u) | ((rgb & 0xffu) << 16);
  return {};
}

std::string parseMemoryLimit(const std::string& text, std::uint64_t& limit) {
  const std::optional<std::uint64_t> bytes = base::parseByteSize(text);
  if (!bytes)
    return "--memory-limit must be BYTES or a number with K, M, G or T (e.g. 4G), not '" + text +
           "'";
  limit = *bytes;
  return {};
}

// --connect's window and codec. Empty when fine.
std::string connectProblem(const Options& o) {
  try {
    wall::parseWindowRequest(o.window);
    wall::service::parseCodec(o.codec);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

// show: a job of the picture renderer for a serving wall. Empty when fine; sets the job's
// options it implies.
std::string showProblem(Options& o, const RawOptions& raw) {
  ShowOptions& s = o.pictures;
  if (o.connect.empty())
    return "show needs --connect HOST:PORT: the serving wall (what `dfbwall serve` printed)";
  if (s.loop && s.once)
    return "--loop and --once: after the last picture, start again or end; choose one";
  if (!std::isfinite(s.fps)) return "--fps must be a finite number";
  if (!raw.background.empty())
    if (std::string problem = parseBackground(raw.background, s.background); !problem.empty())
      return problem;
  if (!raw.memoryLimit.empty())
    if (std::string problem = parseMemoryLimit(raw.memoryLimit, o.memoryLimit); !problem.empty())
      return problem;
  if (std::string problem = connectProblem(o); !problem.empty()) return problem;
  try {
    s.files = renderers::picture::expandPictures(s.arguments);
  } catch (const std::exception& e) {
    return e.what();
  }
  // Every rank waits for each frame's order within the timeout.
  if (s.files.size() > 1 && 1.0 / s.fps >= o.timeoutSeconds)
    return "--fps " + std::to_string(s.fps) + ": a picture every " + std::to_string(1.0 / s.fps) +
           " s is not within --timeout " + std::to_string(o.timeoutSeconds) + " s";
  if (s.files.size() > (1u << 30)) return "show: more than 2^30 pictures";
  o.show = true;
  o.renderer = renderers::picture::kPictureName;
  o.frames = s.once ? static_cast<int>(s.files.size()) : 0;  // 0: until stopped
  o.spp = 1;
  return {};
}

// serve: the processes of one wall, all under mpirun or one on its own. Empty when fine.
std::string serveProblem(Options& o, const RawOptions& raw) {
  if (o.wall.empty()) return "serve needs --wall FILE.toml: the wall it runs";
  if (!raw.captureQuota.empty()) {
    const std::optional<std::uint64_t> bytes = base::parseByteSize(raw.captureQuota);
    if (!bytes)
      return "--capture-quota must be BYTES or a number with K, M, G or T (e.g. 512M), not '" +
             raw.captureQuota + "'";
    o.captureQuota = *bytes;
  }
  if (!raw.background.empty())
    if (std::string problem = parseBackground(raw.background, o.background); !problem.empty())
      return problem;
  if (o.captureEvery > 0 && o.captureDir.empty())
    return "serve --capture-every K needs --capture DIR: the folder the wall's captures go to";
  if (o.process > 0 && o.join.empty())
    return "serve --process " + std::to_string(o.process) +
           " needs --join HOST:PORT: the head of the wall it joins";
  if (o.process > 0 && !o.listen.empty())
    return "serve --listen is for the head (process 0); process " + std::to_string(o.process) +
           " joins it with --join";
  if (o.process <= 0 && !o.join.empty())
    return "serve --join is for --process N > 0; the head (process 0) uses --listen";
  if (o.process <= 0 && o.listen.empty())
    return "serve needs --listen [ADDR:]PORT: where the head takes jobs and processes";
  if (o.process <= 0 && !o.serverKey.empty())
    return "serve --server-key pins the head's key for a joining process (--process N > 0); the "
           "head serves with --curve DIR";
  if ((!o.controlTokenFile.empty() || !o.controlHosts.empty()) && o.control.empty())
    return "serve --control-token-file and --control-host need --control [ADDR:]PORT";
  if (o.process > 0 && !o.control.empty())
    return "serve --control is for the head (process 0): it serves the wall's window manager";
  return {};
}

// The render job: options that contradict each other or name what cannot be written. Empty when
// fine; fills the fields `raw` holds.
std::string renderJobProblem(Options& o, const RawOptions& raw, bool ghostGiven) {
  if (!o.view.empty()) {
    if (o.wall.empty() || !o.connect.empty())
      return "--view DISPLAY needs --wall FILE.toml: the layout that has the display";
    if (!o.image.ends_with(".png"))
      return "--view DISPLAY writes what the display shows to --image FILE.png";
    if (o.offscreen || !o.captureDir.empty() || o.mode != "route" || o.dryRun ||
        !o.previewFile.empty())
      return "--view renders one display in this job, without a wall: no --offscreen, "
             "--capture, --mode, --dry-run or --preview";
    o.viewLayout = std::move(o.wall);
    o.wall.clear();
  }
  if (!o.connect.empty() && !o.wall.empty())
    return "--connect and --wall: the wall you connect to has its own layout";
  if (!o.connect.empty() && (o.offscreen || o.mode != "route"))
    return "--offscreen and --mode are for a wall of this job (--wall); with --connect the wall "
           "decides how it presents and pieces always go straight to it";
  if (o.connect.empty() &&
      (o.wait || !o.token.empty() || !o.tokenFile.empty() || !o.serverKey.empty()))
    return "--token, --token-file, --server-key and --wait are for --connect";
  if (o.connect.empty() && !o.window.empty())
    return "--window is for --connect: a window of a wall that `dfbwall serve` runs (a job of "
           "its own wall, --wall, covers the whole canvas)";
  if (!o.connect.empty())
    if (std::string problem = connectProblem(o); !problem.empty()) return problem;
  if (!raw.memoryLimit.empty())
    if (std::string problem = parseMemoryLimit(raw.memoryLimit, o.memoryLimit); !problem.empty())
      return problem;
  if (!raw.size.empty()) {
    const std::string problem = parseSize(raw.size, o.width, o.height);
    if (!problem.empty()) return problem + " (got '" + raw.size + "')";
    o.sizeGiven = true;
  }
  if (hasWall(o) && o.sizeGiven)
    return "--size and --wall: the canvas of a wall is the bounding box of its displays";
  if (hasWall(o) && !o.image.empty())
    return "--image is for runs without --wall; use --capture DIR to save what the wall shows";
  if (!hasWall(o) && (o.offscreen || !o.captureDir.empty() || o.mode != "route" || o.dryRun))
    return "--offscreen, --capture, --mode and --dry-run need --wall FILE.toml (or --connect)";
  if (!o.cameraPath.empty() && o.orbit != 0.0f)
    return "--camera-path and --orbit both move the camera: choose one";
  if ((!o.controlTokenFile.empty() || !o.controlHosts.empty()) && o.control.empty())
    return "--control-token-file and --control-host need --control [ADDR:]PORT";
  return renderingProblem(o, ghostGiven);
}

}  // namespace

int parseOptions(int argc, char** argv, Options& o, bool print) {
  RelayCommand relay;
  RawOptions raw;
  CommandLine cli(o, relay, raw);
  if (const int code = parseArguments(cli, std::vector<std::string>(argv, argv + argc), print);
      code >= 0)
    return code;
  auto fail = [&](const std::string& message) {
    if (print) std::fprintf(stderr, "%s: error: %s\n", cli.commandName().c_str(), message.c_str());
    return 2;
  };
  // The relay runs before MPI, from apps/Run.cpp, when it comes first.
  if (cli.relay->parsed())
    return fail("relay comes first: dfbwall relay --listen [ADDR:]PORT --wall HOST:PORT");
  o.serve = cli.serve->parsed();
  const std::string problem =
      o.serve              ? serveProblem(o, raw)
      : cli.show->parsed() ? showProblem(o, raw)
                           : renderJobProblem(o, raw, cli.root.get_option("--ghost")->count() > 0);
  return problem.empty() ? -1 : fail(problem);
}

int parseRelayOptions(int argc, char** argv, RelayCommand& c) {
  Options unused;
  RawOptions raw;
  CommandLine cli(unused, c, raw);
  std::vector<std::string> args{"dfbwall"};
  args.insert(args.end(), argv, argv + argc);  // argv[0] is "relay"
  if (const int code = parseArguments(cli, args, true); code >= 0) return code;
  const char* missing = c.listen.empty() ? "--listen [ADDR:]PORT: where jobs connect"
                        : c.wall.empty() ? "--wall HOST:PORT: the wall it forwards to"
                                         : nullptr;
  if (!missing) return -1;
  std::fprintf(stderr, "dfbwall relay: error: relay needs %s\n", missing);
  return 2;
}

}  // namespace app
