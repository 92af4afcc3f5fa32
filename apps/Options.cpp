#include "apps/Options.h"

#include <CLI/CLI.hpp>

#include "base/MemoryBudget.h"
#include "wall/layout/Layout.h"
#include "wall/service/protocol/Codec.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

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

}  // namespace

int parseOptions(int argc, char** argv, Options& o, bool print) {
  CLI::App cli{
      "dfbwall: path-traces a scene on MPI ranks and shows it on a display wall through the "
      "Distributed FrameBuffer.\n  image: mpirun -np N dfbwall --scene S --size WxH --image "
      "out.png\n"
      "  wall:  mpirun -np R+W dfbwall --wall configs/walls/2x2.toml --offscreen --capture DIR"};
  std::string size;
  cli.add_option(
         "--scene", o.scene,
         "FILE.toml or builtin:NAME (cornell, spheres; for --renderer scivis: wavelet, particles)")
      ->capture_default_str();
  cli.add_option("--size", size, "image size WxH (not with --wall: the layout sets the canvas)");
  cli.add_option("--spp", o.spp, "samples per pixel per frame")
      ->check(CLI::Range(1, 1 << 16))
      ->capture_default_str();
  cli.add_option("--frames", o.frames, "frames to render, accumulated (0: until stopped)")
      ->check(CLI::Range(0, 1 << 30))
      ->capture_default_str();
  cli.add_option("--seed", o.seed, "random seed")->capture_default_str();
  cli.add_option("--image", o.image,
                 "write the last frame on rank 0: .png (tone-mapped) or .pfm (linear)");
  cli.add_option("--tile-size", o.tileSize, "tile size in pixels")
      ->check(CLI::Range(4, 1024))
      ->capture_default_str();
  cli.add_option("--threads", o.threads, "threads per rank (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  cli.add_option("--distribution", o.distribution, "work distribution")
      ->check(CLI::IsMember({"static", "roundrobin", "dynamic"}))
      ->capture_default_str();
  cli.add_option("--bricks", o.bricks,
                 "scivis: cut the scene into N bricks, each rank loads only its own "
                 "(data-parallel; 0: every rank holds the whole scene)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  cli.add_option("--replication", o.replication,
                 "with --bricks: ranks holding each brick (1: data-parallel, all: image-parallel)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  auto* ghost =
      cli.add_option("--ghost", o.ghost,
                     "with --bricks: ghost data around each brick. reach: all that shading rays "
                     "(AO) reach, images equal the unbricked render; layer: one voxel layer for "
                     "interpolation, less memory, AO differs near brick faces")
          ->check(CLI::IsMember({"reach", "layer"}))
          ->capture_default_str();
  cli.add_option("--renderer", o.renderer, "renderer")
      ->check(CLI::IsMember({"pathtracer", "primary", "pattern", "scivis"}))
      ->capture_default_str();
  cli.add_option("--max-depth", o.maxDepth, "maximum path length")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cli.add_option("--exposure", o.exposure, "exposure before tone mapping")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cli.add_flag("--filmic", o.filmic, "filmic tone curve instead of a clamp");
  cli.add_option("--orbit", o.orbit,
                 "camera orbit, DEGREES per frame about the look-at point around the up axis "
                 "(each frame restarts accumulation)")
      ->check(CLI::Range(-360.0f, 360.0f))
      ->capture_default_str();

  cli.add_option("--wall", o.wall, "wall layout (configs/walls/*.toml)");
  cli.add_option("--connect", o.connect,
                 "HOST:PORT of a wall that `dfbwall serve` runs: every rank renders for it");
  cli.add_option("--token", o.token, "with --connect (and serve): the wall's token");
  cli.add_option("--codec", o.codec,
                 "with --connect: how pieces travel: raw, snappy (lossless, plane-delta "
                 "filtered) or jpeg[:QUALITY[:444|422|420]] (lossy, for thin links)")
      ->capture_default_str();
  cli.add_flag("--wait", o.wait, "with --connect: wait for a busy wall instead of failing");
  cli.add_flag("--offscreen", o.offscreen, "present through OSMesa instead of windows");
  cli.add_option("--capture", o.captureDir,
                 "write each display's last frame (and a wall preview) under DIR");
  cli.add_option("--capture-every", o.captureEvery, "capture every K-th frame too")
      ->check(CLI::Range(0, 1 << 30));
  cli.add_option("--stats", o.statsFile, "write per-frame statistics as JSON");
  cli.add_option("--preview", o.previewFile,
                 "assemble the whole-wall preview (at most 1024 cells a side) on rank 0 from "
                 "tiles shrunk on their owners (as the control server does) and write the last "
                 "one to FILE.png");
  cli.add_option("--mode", o.mode,
                 "route: tiles go straight to the displays; gather: through rank 0")
      ->check(CLI::IsMember({"route", "gather"}))
      ->capture_default_str();
  cli.add_flag("--dry-run", o.dryRun, "validate, print the plan, render nothing");
  cli.add_option("--frames-in-flight", o.framesInFlight, "frames rendered ahead of the wall")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cli.add_flag("!--no-compress", o.compress, "send tiles and pieces uncompressed");
  cli.add_flag("--compress-within-host", o.compressWithinHost,
               "compress messages between ranks of one host too (default: only across hosts)");
  cli.add_option("--handler-threads", o.handlerThreads,
                 "threads that decompress and handle received tiles and pieces at once, "
                 "the messenger's inbox thread included (0: the cores; 1: the inbox thread alone)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  cli.add_option("--timeout", o.timeoutSeconds, "seconds before a stalled frame is an error")
      ->check(CLI::Range(1, 86400))
      ->capture_default_str();
  std::string memoryLimit;
  cli.add_option("--memory-limit", memoryLimit,
                 "BYTES, or with a suffix K, M, G, T (e.g. 512M, 4G): what each rank may hold of "
                 "scenes, images and captures; more is refused when read (default: the host's "
                 "memory shared by the job's ranks on it)");
  cli.add_flag("--quiet", o.quiet, "no progress line");
  cli.add_option("--control", o.control,
                 "[ADDR:]PORT: serve the JSON control API on render rank 0 (default address "
                 "127.0.0.1; any other needs a token)");
  cli.add_option("--control-token", o.controlToken,
                 "token clients must send (Authorization: Bearer TOKEN); generated and printed "
                 "when --control binds beyond loopback without one");
  cli.add_option("--max-spp", o.maxSpp,
                 "with --frames 0: samples per pixel after which a still wall stops rendering "
                 "until something changes (0: never)")
      ->check(CLI::Range(0, 1 << 30))
      ->capture_default_str();
  cli.add_option("--camera-path", o.cameraPath,
                 "FILE.toml: camera keyframes (time -> camera) for a reproducible fly-through");

  CLI::App* serve = cli.add_subcommand(
      "serve",
      "run the wall of --wall as a persistent service that render jobs connect to "
      "(mpirun -np W dfbwall serve --wall L --listen [ADDR:]PORT; jobs: dfbwall --connect)");
  serve->add_option("--listen", o.listen,
                    "[ADDR:]PORT of wall process 0's directory, where jobs connect and the other "
                    "processes join (default address 127.0.0.1; any other needs a token, "
                    "generated and printed when not given)");
  serve
      ->add_option("--process", o.process,
                   "start (or restart) only the layout's wall process N, on its own (not under "
                   "mpirun): 0 is the head (needs --listen), the others need --join")
      ->check(CLI::Range(0, wall::kMaxDisplays - 1));
  serve->add_option("--join", o.join,
                    "with --process N > 0: HOST:PORT of the running wall's head (what it prints "
                    "as 'wall service on')");
  serve->fallthrough();  // --wall, --offscreen, --timeout, --stats, --token are the main ones
  // `dfbwall relay` starts before MPI (apps/Relay.cpp parses its options): listed for --help.
  CLI::App* relay = cli.add_subcommand(
      "relay",
      "forward render jobs to a serving wall from hosts that cannot reach it "
      "(dfbwall relay --listen [ADDR:]PORT --wall HOST:PORT; see dfbwall relay --help)");
  relay->allow_extras();
  try {
    cli.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return print ? cli.exit(e) : 0;
  } catch (const CLI::ParseError& e) {
    if (print) std::fprintf(stderr, "dfbwall: error: %s (see --help)\n", e.what());
    return 2;
  }
  auto fail = [&](const std::string& message) {
    if (print) std::fprintf(stderr, "dfbwall: error: %s\n", message.c_str());
    return 2;
  };
  if (relay->parsed())
    return fail("relay comes first: dfbwall relay --listen [ADDR:]PORT --wall HOST:PORT");
  o.serve = serve->parsed();
  if (o.serve && o.wall.empty()) return fail("serve needs --wall FILE.toml: the wall it runs");
  if (o.serve && !o.connect.empty()) return fail("serve and --connect: a wall does not connect");
  if (o.serve && o.process > 0 && o.join.empty())
    return fail("serve --process " + std::to_string(o.process) +
                " needs --join HOST:PORT: the head of the wall it joins");
  if (o.serve && o.process > 0 && !o.listen.empty())
    return fail("serve --listen is for the head (process 0); process " + std::to_string(o.process) +
                " joins it with --join");
  if (o.serve && o.process <= 0 && !o.join.empty())
    return fail("serve --join is for --process N > 0; the head (process 0) uses --listen");
  if (o.serve && o.process <= 0 && o.listen.empty())
    return fail("serve needs --listen [ADDR:]PORT: where the head takes jobs and processes");
  if (!o.connect.empty() && !o.wall.empty())
    return fail("--connect and --wall: the wall you connect to has its own layout");
  if (!o.connect.empty() && (o.offscreen || o.mode != "route"))
    return fail(
        "--offscreen and --mode are for a wall of this job (--wall); with --connect the "
        "wall decides how it presents and pieces always go straight to it");
  if (o.connect.empty() && !o.serve && (o.wait || !o.token.empty()))
    return fail("--token and --wait are for --connect (or serve)");
  if (!o.connect.empty()) {
    try {
      wall::service::parseCodec(o.codec);
    } catch (const std::exception& e) {
      return fail(e.what());
    }
  }
  if (!memoryLimit.empty()) {
    const std::optional<std::uint64_t> bytes = base::parseByteSize(memoryLimit);
    if (!bytes)
      return fail("--memory-limit must be BYTES or a number with K, M, G or T (e.g. 4G), not '" +
                  memoryLimit + "'");
    o.memoryLimit = *bytes;
  }
  if (!size.empty()) {
    const std::string problem = parseSize(size, o.width, o.height);
    if (!problem.empty()) return fail(problem + " (got '" + size + "')");
    o.sizeGiven = true;
  }
  if (hasWall(o) && o.sizeGiven)
    return fail("--size and --wall: the canvas of a wall is the bounding box of its displays");
  if (hasWall(o) && !o.image.empty())
    return fail(
        "--image is for runs without --wall; use --capture DIR to save what the wall shows");
  if (!hasWall(o) && (o.offscreen || !o.captureDir.empty() || o.mode != "route" || o.dryRun))
    return fail(
        "--offscreen, --capture, --mode and --dry-run need --wall FILE.toml (or --connect)");
  if (!o.cameraPath.empty() && o.orbit != 0.0f)
    return fail("--camera-path and --orbit both move the camera: choose one");
  if (!o.controlToken.empty() && o.control.empty())
    return fail("--control-token needs --control [ADDR:]PORT");
  if (o.bricks > 0 && o.renderer != "scivis")
    return fail("--bricks distributes the scivis renderer's data: add --renderer scivis");
  if (ghost->count() > 0 && o.bricks == 0)
    return fail("--ghost chooses the ghost data of bricks: add --bricks N");
  if (o.bricks > 0 && o.distribution == "dynamic")
    return fail("--bricks: tiles are planned by brick; --distribution dynamic does not apply");
  if (o.renderer == "pattern" && o.distribution == "dynamic")
    return fail(
        "--distribution dynamic balances noisy tiles by averaging redundant inputs; the "
        "pattern renderer draws a new picture every frame: use static or roundrobin");
  if (!o.previewFile.empty() && !endsWith(o.previewFile, ".png"))
    return fail("--preview " + o.previewFile + ": the name must end in .png");
  if (!o.image.empty() && !endsWith(o.image, ".png") && !endsWith(o.image, ".pfm"))
    return fail("--image " + o.image +
                ": the name must end in .png (RGBA8) or .pfm (linear float)");
  // CLI11's range checks let NaN through (every comparison with it is false).
  if (!std::isfinite(o.exposure) || !std::isfinite(o.orbit))
    return fail("--exposure and --orbit must be finite numbers");
  if (!o.image.empty()) {
    // The image reaches rank 0 in one MPI gather, whose counts are ints.
    const std::uint64_t bytes =
        std::uint64_t(o.width) * std::uint64_t(o.height) * (endsWith(o.image, ".pfm") ? 16u : 4u);
    if (bytes > std::uint64_t(std::numeric_limits<int>::max()))
      return fail("--image " + o.image + ": a " + std::to_string(o.width) + "x" +
                  std::to_string(o.height) + " image is " + std::to_string(bytes) +
                  " bytes; one gather carries at most 2^31-1 (use a smaller --size, or .png)");
  }
  return -1;
}

int parseRelayOptions(int argc, char** argv, RelayCommand& c) {
  CLI::App cli{
      "dfbwall relay: render jobs connect here (dfbwall --connect RELAY:PORT) instead of to the "
      "wall, from hosts that cannot reach it; pieces are forwarded without being decoded"};
  cli.name("dfbwall relay");
  cli.add_option("--listen", c.listen,
                 "[ADDR:]PORT for jobs (default address 127.0.0.1); jobs are told ADDR, so on a "
                 "gateway give the address the render hosts reach")
      ->required();
  cli.add_option("--wall", c.wall, "HOST:PORT of the wall (what `dfbwall serve` printed)")
      ->required();
  cli.add_option("--timeout", c.timeoutSeconds, "seconds after which a silent job is forgotten")
      ->check(CLI::Range(1, 86400))
      ->capture_default_str();
  cli.add_option("--stats", c.statsFile, "append one JSON line per job to FILE");
  try {
    cli.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return cli.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "dfbwall relay: error: %s (see dfbwall relay --help)\n", e.what());
    return 2;
  }
  return -1;
}

}  // namespace app
