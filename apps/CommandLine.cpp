#include "apps/CommandLine.h"

#include <string>
#include <vector>

#include "wall/image/Thumbnail.h"
#include "wall/layout/Layout.h"

namespace app {
namespace {

// Help groups; a command lists them in the order its options are added.
const std::string kScene = "Scene", kRendering = "Rendering",
                  kBricks = "Data-parallel scivis (bricks)", kWall = "Wall",
                  kConnect = "Connect to a wall service", kControl = "Control",
                  kNetwork = "Network", kNetworkSecurity = "Network and security",
                  kThroughput = "Throughput", kFailures = "Failure handling", kOutput = "Output",
                  kPictures = "Pictures", kHelp = "Help";

// ---- Options of more than one command -------------------------------------------------------

// The render job and serve: the layout whose displays are driven, and how they present.
void addWallGroup(CLI::App& app, std::string& layout, bool& offscreen) {
  app.add_option("--wall", layout, "wall layout FILE.toml (configs/walls/*.toml)")->group(kWall);
  app.add_flag("--offscreen", offscreen, "present through OSMesa instead of windows")->group(kWall);
}

// The render job and serve: frames between rendering and presenting, and the threads that
// handle what arrives. The help says what each means for the command.
void addThroughputGroup(CLI::App& app, int& framesInFlight, const std::string& framesInFlightHelp,
                        int& handlerThreads, const std::string& handlerThreadsHelp) {
  app.add_option("--frames-in-flight", framesInFlight, framesInFlightHelp)
      ->check(CLI::Range(1, 8))
      ->capture_default_str()
      ->group(kThroughput);
  app.add_option("--handler-threads", handlerThreads, handlerThreadsHelp)
      ->check(CLI::Range(0, 256))
      ->capture_default_str()
      ->group(kThroughput);
}

// Every command: how long a silent peer may stay silent.
void addTimeout(CLI::App& app, int& seconds, const std::string& help) {
  app.add_option("--timeout", seconds, help)
      ->check(CLI::Range(1, 86400))
      ->capture_default_str()
      ->group(kFailures);
}

// Every command: JSON statistics to a file.
void addStats(CLI::App& app, std::string& file, const std::string& help) {
  app.add_option("--stats", file, help)->group(kOutput);
}

// serve and relay: where render jobs connect.
void addListen(CLI::App& app, std::string& address, const std::string& group,
               const std::string& help) {
  app.add_option("--listen", address, help)->group(group);
}

// The render job (with --connect), serve and relay: the wall's token, and the wall's public key
// to pin (docs/security.md, "The wall service").
void addWallCredentials(CLI::App& app, std::string& token, std::string& tokenFile,
                        std::string& serverKey, const std::string& group,
                        const std::string& tokenFileHelp, const std::string& serverKeyHelp) {
  app.add_option("--token-file", tokenFile,
                 tokenFileHelp +
                     " (default: $DFBWALL_TOKEN, else "
                     "~/.local/state/dfbwall/wall-token)")
      ->group(group);
  app.add_option("--token", token,
                 "the wall's token itself: visible in ps, for tests (use --token-file or "
                 "DFBWALL_TOKEN)")
      ->group(group);
  app.add_option("--server-key", serverKey, serverKeyHelp)->group(group);
}

// serve and relay: serve every socket with CURVE.
void addCurve(CLI::App& app, std::string& dir, const std::string& group) {
  app.add_option("--curve", dir,
                 "DIR of a key pair (dfbwall keygen DIR): every socket encrypted with CURVE; "
                 "clients pin DIR/wall-public.key with --server-key")
      ->group(group);
}

// Last, so that every command lists it after its own groups.
void addHelp(CLI::App& app) {
  app.set_help_flag("-h,--help", "print this help and exit")->group(kHelp);
}

// ---- The render job -------------------------------------------------------------------------

void addSceneGroup(CLI::App& app, Options& o) {
  app.add_option(
         "--scene", o.scene,
         "FILE.toml or builtin:NAME (cornell, spheres; for --renderer scivis: wavelet, particles)")
      ->capture_default_str()
      ->group(kScene);
  app.add_option("--camera-path", o.cameraPath,
                 "FILE.toml: camera keyframes (time -> camera) for a reproducible fly-through")
      ->group(kScene);
  app.add_option("--orbit", o.orbit,
                 "camera orbit, DEGREES per frame about the look-at point around the up axis "
                 "(each frame restarts accumulation)")
      ->check(CLI::Range(-360.0f, 360.0f))
      ->capture_default_str()
      ->group(kScene);
}

void addRenderingGroup(CLI::App& app, Options& o, RawOptions& raw) {
  app.add_option("--renderer", o.renderer, "renderer")
      ->check(CLI::IsMember({"pathtracer", "primary", "pattern", "scivis"}))
      ->capture_default_str()
      ->group(kRendering);
  app.add_option("--size", raw.size, "image size WxH (not with --wall: the layout sets the canvas)")
      ->group(kRendering);
  app.add_option("--spp", o.spp, "samples per pixel per frame")
      ->check(CLI::Range(1, 1 << 16))
      ->capture_default_str()
      ->group(kRendering);
  app.add_option("--frames", o.frames, "frames to render, accumulated (0: until stopped)")
      ->check(CLI::Range(0, 1 << 30))
      ->capture_default_str()
      ->group(kRendering);
  app.add_option("--seed", o.seed, "random seed")->capture_default_str()->group(kRendering);
  app.add_option("--max-depth", o.maxDepth, "maximum path length")
      ->check(CLI::Range(1, 64))
      ->capture_default_str()
      ->group(kRendering);
  app.add_option("--exposure", o.exposure, "exposure before tone mapping")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->group(kRendering);
  app.add_flag("--filmic", o.filmic, "filmic tone curve instead of a clamp")->group(kRendering);
  app.add_option("--tile-size", o.tileSize, "tile size in pixels")
      ->check(CLI::Range(4, 1024))
      ->capture_default_str()
      ->group(kRendering);
  app.add_option("--threads", o.threads, "threads per rank (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str()
      ->group(kRendering);
  app.add_option("--distribution", o.distribution, "work distribution")
      ->check(CLI::IsMember({"static", "roundrobin", "dynamic"}))
      ->capture_default_str()
      ->group(kRendering);
}

void addBricksGroup(CLI::App& app, Options& o) {
  app.add_option("--bricks", o.bricks,
                 "scivis: cut the scene into N bricks, each rank loads only its own "
                 "(data-parallel; 0: every rank holds the whole scene)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str()
      ->group(kBricks);
  app.add_option("--replication", o.replication,
                 "with --bricks: ranks holding each brick (1: data-parallel, all: image-parallel)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str()
      ->group(kBricks);
  app.add_option("--ghost", o.ghost,
                 "with --bricks: ghost data around each brick. reach: all that shading rays "
                 "(AO) reach, images equal the unbricked render; layer: one voxel layer for "
                 "interpolation, less memory, AO differs near brick faces")
      ->check(CLI::IsMember({"reach", "layer"}))
      ->capture_default_str()
      ->group(kBricks);
}

// The wall of this job: its last W ranks drive the layout's displays.
void addJobWallOptions(CLI::App& app, Options& o) {
  app.add_option("--mode", o.mode,
                 "route: tiles go straight to the displays; gather: through rank 0")
      ->check(CLI::IsMember({"route", "gather"}))
      ->capture_default_str()
      ->group(kWall);
  app.add_flag("--dry-run", o.dryRun,
               "validate, print the plan (which tiles go where), render nothing")
      ->group(kWall);
}

void addConnectGroup(CLI::App& app, Options& o) {
  app.add_option("--connect", o.connect,
                 "HOST:PORT of a wall that `dfbwall serve` runs (or a relay): every rank renders "
                 "for it")
      ->group(kConnect);
  addWallCredentials(app, o.token, o.tokenFile, o.serverKey, kConnect,
                     "with --connect: FILE holding the wall's token",
                     "with --connect: FILE of the wall's CURVE public key (serve --curve): "
                     "encrypt, and refuse a wall that does not hold it");
  app.add_option("--codec", o.codec,
                 "with --connect: how pieces travel: raw, snappy (lossless, plane-delta "
                 "filtered) or jpeg[:QUALITY[:444|422|420]] (lossy, for thin links)")
      ->capture_default_str()
      ->group(kConnect);
  app.add_flag("--wait", o.wait, "with --connect: wait for a busy wall instead of failing")
      ->group(kConnect);
  app.add_option("--window", o.window,
                 "with --connect: the part of the wall this job covers: X,Y,W,H (wall canvas "
                 "pixels, bezels included), a display's name, or full (default)")
      ->group(kConnect);
}

void addControlGroup(CLI::App& app, Options& o) {
  app.add_option("--control", o.control,
                 "[ADDR:]PORT: serve the JSON control API and the controller page on render rank "
                 "0 (default address 127.0.0.1); always behind a token, generated and printed "
                 "as the address to open unless --control-token-file or DFBWALL_CONTROL_TOKEN "
                 "gives it")
      ->group(kControl);
  app.add_option("--control-token-file", o.controlTokenFile,
                 "FILE holding the control API's token (created mode 0600 with a fresh one when "
                 "absent); clients send Authorization: Bearer TOKEN")
      ->group(kControl);
  app.add_option("--control-host", o.controlHosts,
                 "NAME: a host name clients reach the control API by, besides its address and "
                 "localhost (other Host headers get 403); repeatable")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->group(kControl);
  app.add_option("--max-spp", o.maxSpp,
                 "with --frames 0: samples per pixel after which a still wall stops rendering "
                 "until something changes (0: never)")
      ->check(CLI::Range(0, 1 << 30))
      ->capture_default_str()
      ->group(kControl);
}

// How tiles and pieces travel between the job's ranks.
void addJobMessagingOptions(CLI::App& app, Options& o) {
  app.add_flag("!--no-compress", o.compress, "send tiles and pieces uncompressed")
      ->group(kThroughput);
  app.add_flag("--compress-within-host", o.compressWithinHost,
               "compress messages between ranks of one host too (default: only across hosts)")
      ->group(kThroughput);
}

void addJobFailureOptions(CLI::App& app, RawOptions& raw) {
  app.add_option("--memory-limit", raw.memoryLimit,
                 "BYTES, or with a suffix K, M, G, T (e.g. 512M, 4G): what each rank may hold of "
                 "scenes, images and captures; more is refused when read (default: the host's "
                 "memory shared by the job's ranks on it)")
      ->group(kFailures);
}

void addJobOutputGroup(CLI::App& app, Options& o) {
  app.add_option("--view", o.view,
                 "DISPLAY[,DISPLAY...] with --wall and --image: render what those displays of "
                 "the layout show, in this job alone (no wall ranks): the references for their "
                 "captures; {display} in --image's name is each display's name")
      ->group(kOutput);
  app.add_option("--image", o.image,
                 "without a wall: write the last frame on rank 0: .png (tone-mapped) or .pfm "
                 "(linear)")
      ->group(kOutput);
  app.add_option("--capture", o.captureDir,
                 "with a wall: write each display's last frame (and a wall preview) under DIR "
                 "(with --connect: a folder inside the wall's serve --capture-root)")
      ->group(kOutput);
  app.add_option("--capture-every", o.captureEvery, "with --capture: every K-th frame too")
      ->check(CLI::Range(0, 1 << 30))
      ->group(kOutput);
  app.add_option("--preview", o.previewFile,
                 "assemble the whole-wall preview (at most 1024 cells a side) on rank 0 from "
                 "tiles shrunk on their owners (as the control server does) and write the last "
                 "one to FILE.png")
      ->group(kOutput);
  addStats(app, o.statsFile, "write per-frame statistics as JSON Lines to FILE");
  app.add_flag("--quiet", o.quiet, "no progress line")->group(kOutput);
}

void addRenderJob(CLI::App& app, Options& o, RawOptions& raw) {
  // An option given again takes its last value: scripts/demo adds the caller's options after
  // its own (`scripts/demo --frames 64`).
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  addSceneGroup(app, o);
  addRenderingGroup(app, o, raw);
  addBricksGroup(app, o);
  addWallGroup(app, o.wall, o.offscreen);
  addJobWallOptions(app, o);
  addConnectGroup(app, o);
  addControlGroup(app, o);
  addThroughputGroup(app, o.framesInFlight, "frames rendered ahead of the wall", o.handlerThreads,
                     "threads that decompress and handle received tiles and pieces at once, the "
                     "messenger's inbox thread included (0: the cores; 1: the inbox thread alone)");
  addJobMessagingOptions(app, o);
  addTimeout(app, o.timeoutSeconds, "seconds any wait may take before it is an error");
  addJobFailureOptions(app, raw);
  addJobOutputGroup(app, o);
  addHelp(app);
}

// ---- serve and relay ------------------------------------------------------------------------

// serve --control: the wall's own window manager on the head, with the job's --control rules.
void addWallControl(CLI::App& serve, Options& o) {
  serve
      .add_option("--control", o.control,
                  "[ADDR:]PORT: the head (process 0) serves the wall's window manager (JSON API "
                  "and page: list, raise, close the jobs' windows) there (default address "
                  "127.0.0.1); always behind a token, as a job's --control")
      ->group(kControl);
  serve
      .add_option("--control-token-file", o.controlTokenFile,
                  "FILE holding the window manager's token (created mode 0600 with a fresh one "
                  "when absent); clients send Authorization: Bearer TOKEN")
      ->group(kControl);
  serve
      .add_option("--control-host", o.controlHosts,
                  "NAME: a host name clients reach the window manager by, besides its address "
                  "and localhost (other Host headers get 403); repeatable")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->group(kControl);
  serve
      .add_option("--thumbnail-size", o.thumbnailSize,
                  "N: the longest side of the windows' live thumbnails on the window manager's "
                  "page, in pixels (default: 320; made with --max-jobs above 1 only)")
      ->check(CLI::Range(16, wall::kMaxThumbnailSide))
      ->group(kControl);
}

void addServe(CLI::App& serve, Options& o, RawOptions& raw) {
  addWallGroup(serve, o.wall, o.offscreen);
  serve
      .add_option("--max-jobs", o.maxJobs,
                  "N: jobs on the wall at once, each in its window, the newest on top; a job "
                  "beyond them is refused busy or waits with --wait (default: 4; 1: one job "
                  "at a time, on the whole wall)")
      ->check(CLI::Range(1, 16))
      ->group(kWall);
  addListen(serve, o.listen, kNetworkSecurity,
            "[ADDR:]PORT of wall process 0's directory, where jobs connect and the other "
            "processes join (default address 127.0.0.1)");
  serve
      .add_option("--process", o.process,
                  "start (or restart) only the layout's wall process N, on its own (not under "
                  "mpirun): 0 is the head (needs --listen), the others need --join")
      ->check(CLI::Range(0, wall::kMaxDisplays - 1))
      ->group(kNetworkSecurity);
  serve
      .add_option("--join", o.join,
                  "with --process N > 0: HOST:PORT of the running wall's head (what it prints "
                  "as 'wall service on')")
      ->group(kNetworkSecurity);
  serve
      .add_option("--advertise", o.advertise,
                  "HOST: the address jobs (and the head) are told to dial for this process, one "
                  "it listens on (default: the --listen address, or with 0.0.0.0 this host's "
                  "first)")
      ->group(kNetworkSecurity);
  addWallCredentials(serve, o.token, o.tokenFile, o.serverKey, kNetworkSecurity,
                     "FILE holding the token every job, relay and process must present (created "
                     "mode 0600 with a new token when absent)",
                     "with --process N > 0: FILE of the head's CURVE public key (default with "
                     "--curve DIR: DIR/wall-public.key)");
  addCurve(serve, o.curveDir, kNetworkSecurity);
  addThroughputGroup(serve, o.framesInFlight, "the most frames a job may render ahead of the wall",
                     o.handlerThreads,
                     "threads of each wall process that decode received pieces at once (0: the "
                     "cores)");
  addTimeout(serve, o.timeoutSeconds,
             "seconds after which a silent job or wall process is dropped");
  addStats(serve, o.statsFile,
           "wall process 0: append one JSON line per job and per process lost or back to FILE");
  addWallControl(serve, o);
  serve
      .add_option("--capture-root", o.captureRoot,
                  "an existing folder: a job's --capture names a folder inside it (relative to "
                  "it, or absolute within it); without it, jobs that ask for captures are refused")
      ->group(kOutput);
  serve
      .add_option("--capture-quota", raw.captureQuota,
                  "BYTES, or with a suffix K, M, G, T: the most one job's captures may take on "
                  "each wall process; a capture past it ends the job (default: 1G); the wall's own "
                  "--capture gets as much over its run, then stops capturing")
      ->group(kOutput);
  serve
      .add_option("--capture", o.captureDir,
                  "write what each of this process's displays shows (the jobs' windows over "
                  "the background) as DIR/<display>/frame-N.png, N the wall's presented-frame "
                  "count (with --max-jobs above 1: this process's; a folder outside "
                  "--capture-root; made when missing)")
      ->group(kOutput);
  serve
      .add_option("--capture-every", o.captureEvery,
                  "with --capture: every K-th presented frame (default: 1, every frame)")
      ->check(CLI::Range(1, 1 << 30))
      ->group(kOutput);
  serve
      .add_option("--background", raw.background,
                  "#rrggbb: what the displays show outside a job's --window (default: black)")
      ->group(kOutput);
  addHelp(serve);
}

void addRelay(CLI::App& relay, RelayCommand& c) {
  addListen(
      relay, c.listen, kNetwork,
      "required: [ADDR:]PORT for jobs (default address 127.0.0.1); jobs are told ADDR, so on a "
      "gateway give the address the render hosts reach");
  relay
      .add_option("--wall", c.wall,
                  "required: HOST:PORT of the wall (what `dfbwall serve` printed)")
      ->group(kNetwork);
  addWallCredentials(relay, c.token, c.tokenFile, c.serverKey, kNetwork,
                     "FILE holding the wall's token: jobs must present it, and the relay does to "
                     "the wall",
                     "FILE of the wall's CURVE public key (serve --curve): the relay encrypts its "
                     "links to the wall, and refuses a wall that does not hold it");
  addCurve(relay, c.curveDir, kNetwork);
  addTimeout(relay, c.timeoutSeconds, "seconds after which a silent job is forgotten");
  addStats(relay, c.statsFile, "append one JSON line per job to FILE");
  addHelp(relay);
}

// ---- show -----------------------------------------------------------------------------------

void addShow(CLI::App& show, Options& o, RawOptions& raw) {
  ShowOptions& s = o.pictures;
  show.add_option("IMAGE", s.arguments,
                  "PNG or JPEG files, or numbered sequences (plot-%04d.png: every number from the "
                  "lowest to the highest, no gap), shown one after another")
      ->required()
      ->group(kPictures);
  show.add_option("--fps", s.fps, "pictures per second when there are several")
      ->check(CLI::Range(0.01, 1000.0))
      ->capture_default_str()
      ->group(kPictures);
  show.add_flag("--loop", s.loop, "after the last picture, start again from the first")
      ->group(kPictures);
  show.add_flag("--once", s.once,
                "end after the last picture is shown (default: keep showing it until stopped)")
      ->group(kPictures);
  show.add_option("--filter", s.filter, "how a picture is scaled into the window")
      ->check(CLI::IsMember({"bilinear", "nearest"}))
      ->capture_default_str()
      ->group(kPictures);
  show.add_option("--background", raw.background,
                  "#rrggbb: around the picture (it keeps its aspect) and under its transparent "
                  "parts (default: black)")
      ->group(kPictures);
  addConnectGroup(show, o);
  addTimeout(show, o.timeoutSeconds, "seconds any wait may take before it is an error");
  addJobFailureOptions(show, raw);
  show.add_option("--capture", o.captureDir,
                  "a folder inside the wall's serve --capture-root: write the window's part of "
                  "each display, the last frame (and every K-th with --capture-every)")
      ->group(kOutput);
  show.add_option("--capture-every", o.captureEvery, "with --capture: every K-th frame too")
      ->check(CLI::Range(0, 1 << 30))
      ->group(kOutput);
  addStats(show, o.statsFile, "write per-frame statistics as JSON Lines to FILE");
  show.add_flag("--quiet", o.quiet, "no progress line")->group(kOutput);
  addHelp(show);
}

// The commands that take `option` ("--scene"), as a message names them.
std::vector<std::string> commandsTaking(const CommandLine& cli, const std::string& option) {
  std::vector<std::string> names;
  if (cli.root.get_option_no_throw(option)) names.push_back("the render job (dfbwall)");
  for (const CLI::App* sub : {cli.serve, cli.relay, cli.show})
    if (sub->get_option_no_throw(option)) names.push_back("dfbwall " + sub->get_name());
  return names;
}

// "--scene" of "--scene=x"; empty when `argument` is no option.
std::string optionName(const std::string& argument) {
  const std::string name = argument.substr(0, argument.find('='));
  return name.size() > 1 && name[0] == '-' && name != "--" ? name : std::string();
}

}  // namespace

CommandLine::CommandLine(Options& options, RelayCommand& relayCommand, RawOptions& raw)
    : root(
          "dfbwall: path-traces a scene on MPI ranks and shows it on a display wall through "
          "the Distributed FrameBuffer.\n"
          "  image: mpirun -np N dfbwall --scene S --size WxH --image out.png\n"
          "  wall:  mpirun -np R+W dfbwall --wall configs/walls/2x2.toml --offscreen --capture "
          "DIR\n"
          "These options are the render job's; serve, relay and show take their own "
          "(dfbwall serve --help, dfbwall relay --help, dfbwall show --help).",
          "dfbwall") {
  addRenderJob(root, options, raw);
  serve = root.add_subcommand(
      "serve",
      "run the wall of --wall as a persistent service that render jobs connect to "
      "(mpirun -np W dfbwall serve --wall L --listen [ADDR:]PORT; jobs: dfbwall --connect)");
  addServe(*serve, options, raw);
  relay = root.add_subcommand(
      "relay",
      "forward render jobs to a serving wall from hosts that cannot reach it, without decoding "
      "their pieces (dfbwall relay --listen [ADDR:]PORT --wall HOST:PORT; jobs: dfbwall "
      "--connect RELAY:PORT)");
  addRelay(*relay, relayCommand);
  show = root.add_subcommand(
      "show",
      "put ready-made pictures (PNG, JPEG, numbered sequences) in a window of a serving wall, "
      "sent as a render job's frames (dfbwall show --connect HOST:PORT [--window W] IMAGE...)");
  addShow(*show, options, raw);
  root.require_subcommand(0, 1);
  // Arguments a command does not take are kept, not thrown at: misplacedArgument names them
  // with the command and where they belong.
  for (CLI::App* app : {&root, serve, relay, show}) app->allow_extras();
}

const CLI::App& CommandLine::command() const {
  if (serve->parsed()) return *serve;
  if (relay->parsed()) return *relay;
  if (show->parsed()) return *show;
  return root;
}

std::string CommandLine::commandName() const {
  const CLI::App& given = command();
  return &given == &root ? "dfbwall" : "dfbwall " + given.get_name();
}

std::string CommandLine::misplacedArgument() const {
  const CLI::App& given = command();
  const std::string name = &given == &root ? "the render job" : given.get_name();
  const std::string seeHelp = " (see " + commandName() + " --help)";
  std::vector<std::string> stray;
  if (&given != &root) {
    // What came before the subcommand's name went to the render job.
    stray = root.remaining();
    for (const CLI::Option* option : root.get_options())
      if (option->count() > 0) stray.push_back(option->get_name());
    for (const std::string& argument : stray)
      if (const std::string option = optionName(argument);
          !option.empty() && given.get_option_no_throw(option))
        return option + " was given before " + name + "; its options go after it (" +
               commandName() + " " + option + " ...)";
  }
  for (const std::string& argument : given.remaining()) stray.push_back(argument);
  if (stray.empty()) return {};
  const std::string option = optionName(stray.front());
  if (option.empty()) return "unexpected argument '" + stray.front() + "'" + seeHelp;
  const std::vector<std::string> others = commandsTaking(*this, option);
  std::string list;
  for (size_t i = 0; i < others.size(); ++i)
    list += (i == 0 ? "" : i + 1 == others.size() ? " and " : ", ") + others[i];
  return option + " is not an option of " + name +
         (others.empty() ? "" : "; " + list + (others.size() > 1 ? " take it" : " takes it")) +
         seeHelp;
}

}  // namespace app
