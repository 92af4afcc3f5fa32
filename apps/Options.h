#pragma once
// The dfbwall command line, parsed into plain values: the render job (dfbwall itself) and the
// `serve` and `relay` subcommands, each with only the options it reads (apps/CommandLine.h).
// Every rank parses the same arguments and gets the same answer, so a bad option is caught
// everywhere at once.
#include <cstdint>
#include <string>
#include <vector>

namespace app {

// `dfbwall show`: ready-made pictures in a window of a serving wall, played as a job's frames
// (renderers/picture/PictureRenderer.h). The connection options are the job's (Options below).
struct ShowOptions {
  std::vector<std::string> arguments;      // as given: files and numbered sequences
  std::vector<std::string> files;          // expanded, in play order
  double fps = 1;                          // pictures per second of a sequence
  bool loop = false, once = false;         // after the last: start again / end (default: hold it)
  std::string filter = "bilinear";         // nearest | bilinear
  std::uint32_t background = 0xff000000u;  // RGBA8 around the picture (black)
};

// The render job's options, and serve's (marked below): serve reads only those marked.
struct Options {
  // Scene and rendering.
  std::string scene = "builtin:cornell";
  int width = 512, height = 512;
  bool sizeGiven = false;
  int spp = 1;
  int frames = 1;  // 0: until stopped (a signal, POST /api/stop, a closed window)
  std::uint64_t seed = 0;
  std::string image;  // .png: tone-mapped RGBA8; .pfm: linear radiance
  int tileSize = 64;
  int threads = 0;
  std::string distribution = "roundrobin";
  std::string renderer = "pathtracer";
  int maxDepth = 8;
  float exposure = 1.0f;
  bool filmic = false;
  float orbit = 0.0f;
  // Data-parallel (scivis): the scene cut into this many bricks (0: every rank holds it whole),
  // each held by `replication` ranks.
  int bricks = 0;
  int replication = 1;
  // How much ghost data each brick loads: "reach" (as far as shading rays reach: bricked images
  // equal the whole scene's) or "layer" (one voxel layer: less memory, AO seams at brick faces).
  std::string ghost = "reach";

  // The wall.
  std::string wall;  // layout file; empty: no wall (serve: the wall it runs)
  // --view DISPLAY[,DISPLAY...] with --wall: no wall, an image of what each display shows
  // (--image, kViewedDisplay in its name replaced by the display's). The parser moves --wall's
  // file here, so the job has no wall ranks.
  std::string view, viewLayout;
  bool offscreen = false;  // serve too
  std::string captureDir;
  int captureEvery = 0;
  std::string statsFile;       // serve too: one JSON line per job
  std::string previewFile;     // .png: the last whole-wall preview, assembled on rank 0
  std::string mode = "route";  // route | gather
  bool dryRun = false;
  int framesInFlight = 2;  // serve too: the most it grants a job
  bool compress = true;
  bool compressWithinHost = false;
  int handlerThreads = 0;   // serve too: threads handling received pieces at once; 0: the cores
  int timeoutSeconds = 60;  // serve too
  // Bytes each rank may hold of data sized by its input (base/MemoryBudget.h); 0: the host's
  // memory shared by the job's ranks on it.
  std::uint64_t memoryLimit = 0;
  bool quiet = false;

  // The wall as a service. `dfbwall serve`: these processes are the wall of `wall`, listening
  // for render jobs on `listen`. `--connect`: this job renders for such a wall.
  bool serve = false;
  std::string listen;       // serve, the head: [ADDR:]PORT
  int process = -1;         // serve --process N: this is the layout's process N, alone
  std::string join;         // serve --join HOST:PORT: the head a process N > 0 joins
  std::string connect;      // HOST:PORT of a serving wall; empty: none
  std::string token;        // serve, connect: the wall's token (tests: visible in ps)
  std::string tokenFile;    // serve, connect: the file holding it (serve creates it)
  std::string serverKey;    // connect, serve --join: the wall's public key (CURVE)
  std::string curveDir;     // serve: the wall's key pair; every socket CURVE
  std::string advertise;    // serve: the address others are told to dial for this process
  std::string captureRoot;  // serve: jobs' captures only beneath it; empty: none taken
  std::uint64_t captureQuota = std::uint64_t(1) << 30;  // serve: bytes per job and process
  std::string codec = "snappy";  // connect: raw | snappy | jpeg[:QUALITY[:SUBSAMPLING]]
  bool wait = false;             // connect: queue behind a connected job instead of failing
  std::string window;            // connect: full | X,Y,W,H | DISPLAY (wall/layout/Window.h)
  std::uint32_t background = 0xff000000u;  // serve: RGBA8 outside a job's window (black)
  int maxJobs = 4;                         // serve: jobs on the wall at once (--max-jobs)
  int thumbnailSize = 320;                 // serve --control: the thumbnails' longest side

  // Steering.
  std::string control;           // [ADDR:]PORT of the control server on render rank 0; empty: none
  std::string controlTokenFile;  // the control API's secret (apps/ControlSecret.h)
  std::vector<std::string> controlHosts;  // more names a Host header may carry (rebinding)
  std::int64_t maxSpp = 1024;  // with --frames 0: idle once an epoch has this many samples
  std::string cameraPath;      // FILE.toml: keyframes (apps/CameraPath.h)

  // `dfbwall show`: a job of the renderer "picture" with --connect.
  bool show = false;
  ShowOptions pictures;
};

// Parses argv (the render job, `serve ...` or `show ...`). Returns an exit code to stop with (0
// after --help) or -1 to go on; messages go to stdout/stderr only when `print` (rank 0).
int parseOptions(int argc, char** argv, Options& options, bool print);
// True when the hub or the wall is on the other end: a wall of this job (--wall) or a serving
// wall (--connect).
// In --image's name with --view: replaced by each display's name.
inline constexpr const char* kViewedDisplay = "{display}";

inline bool hasWall(const Options& o) { return !o.wall.empty() || !o.connect.empty(); }

// `dfbwall relay` (apps/Relay.cpp): argv from "relay" on. Same return convention.
struct RelayCommand {
  std::string listen, wall, statsFile;
  std::string token, tokenFile, serverKey, curveDir;  // as serve's and the job's
  int timeoutSeconds = 60;
};
int parseRelayOptions(int argc, char** argv, RelayCommand& command);

}  // namespace app
