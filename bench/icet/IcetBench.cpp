// Sort-last compositing side by side: the DFB (compositing while the bricks render, as
// `dfbwall --renderer scivis --bricks N` does) against IceT (compositing the finished full-frame
// images, as ParaView and the paper's section 6.2.1 do), on the same bricks of the same scene,
// in one MPI job with the variants interleaved frame by frame (dfb, icet-reduce, icet-radixk,
// then the next frame in a rotated order), so the machine's noise hits all of them alike.
//
//   mpirun -np N icet_bench --scene S.toml --mode transparent|opaque --size WxH --frames F
//          [--orbit DEG] [--threads T] [--tiles 1x1|2x2] [--variants dfb,icet-reduce,icet-radixk]
//          [--images DIR]
//   icet_bench --compare A.png B.png       (largest channel difference of two PNGs)
//
// One brick per rank. transparent: premultiplied float RGBA, the DFB's RGBAF32 image vs IceT's
// ordered float blending (icetCompositeOrder = the bricks' visibility order); opaque: the
// scene's surfaces made opaque and its volumes hidden (z-compositing keeps only the nearest
// fragment, so it is right only for opaque surfaces), the DFB's RGBA8 image vs IceT's z-buffer
// compositing of RGBA8 + depth. --tiles 1x1: the finished image ends on rank 0 (the DFB's
// gather, IceT's single tile). --tiles 2x2 (the display-wall case): IceT with 4 tiles, tile
// ty*2+tx shown by rank ty*2+tx; the DFB as dfbwall's route mode (display format NONE, each
// finished tile tone-mapped on its owner, cut at display borders and sent to the display's rank,
// here the same ranks 0-3), so its displays hold RGBA8.
//
// Per frame and variant rank 0 prints one JSON line: total_ms (barrier → finished image on the
// last display rank), render_ms (slowest rank's local rendering), overhead_ms (the paper's
// compositing overhead: the slowest rank's last local render → the finished image on every
// display rank; all ranks on one host, whose steady clock is system-wide), icet_bytes_sent.
// With --images, the last frame's images are written as PNGs and every IceT image is compared
// with the DFB's (linear radiance for 1x1 transparent, else 8-bit levels).
#include <mpi.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "base/Timing.h"
#include "bench/icet/BrickImage.h"
#include "bench/icet/IcetCompositor.h"
#include "bench/icet/PieceReceiver.h"
#include "dfb/DistributedFrameBuffer.h"
#include "messaging/Messenger.h"
#include "messaging/MpiSession.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/scivis/Registration.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "wall/image/Png.h"
#include "wall/layout/Ranks.h"
#include "wall/route/DisplayRoutingOp.h"
#include "wall/route/PieceMessage.h"

namespace {

using base::Clock;
using Json = nlohmann::json;

struct Options {
  std::string scene, mode = "transparent", size = "1024x1024", tiles = "1x1";
  std::string variants = "dfb,icet-reduce,icet-radixk", images;
  int frames = 8, threads = 1;
  float orbit = 3.0f;
  std::uint64_t seed = 1;
};

// One rank's time points of one variant-frame, gathered to rank 0.
struct Sample {
  std::int64_t start, rendered, finished;  // steady_clock ns
  double renderMs;
  std::int32_t display;  // 1: this rank holds (part of) the finished image
  std::int32_t pad;
};

std::int64_t ns(Clock::time_point t) { return t.time_since_epoch().count(); }

std::vector<std::string> split(const std::string& s, char c) {
  std::vector<std::string> out;
  std::size_t a = 0;
  while (a <= s.size()) {
    const std::size_t b = std::min(s.find(c, a), s.size());
    if (b > a) out.push_back(s.substr(a, b - a));
    a = b + 1;
  }
  return out;
}

void parseSize(const std::string& s, int& w, int& h) {
  if (std::sscanf(s.c_str(), "%dx%d", &w, &h) != 2 || w < 1 || h < 1)
    throw std::runtime_error("bad size '" + s + "' (WxH)");
}

// The finished image of a variant on rank 0, as RGBA8 for PNGs and (transparent) linear floats.
struct Finished {
  std::vector<std::uint32_t> rgba8;
  std::vector<float> linear;
};

// What one rank shows of the finished image: a rectangle of the canvas (x, y, w, h) and its
// pixels, linear float RGBA (`blend`) or RGBA8. Empty on ranks that show nothing.
struct Part {
  bool shown = false;
  std::array<int, 4> rect{0, 0, 0, 0};
  std::vector<float> linear;
  std::vector<std::uint32_t> rgba8;
};

// Each display rank's part to rank 0 (outside the timed part), assembled on the canvas.
Finished assemble(const Part& mine, bool blend, int width, int height, MPI_Comm comm) {
  int rank = 0, size = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  Finished out;
  if (rank == 0) {
    out.rgba8.assign(static_cast<std::size_t>(width) * height, 0);
    if (blend) out.linear.assign(4 * out.rgba8.size(), 0.0f);
  }
  for (int r = 0; r < size; ++r) {
    std::array<int, 5> head{0, 0, 0, 0, 0};  // has tile, rect
    std::vector<float> f;
    std::vector<std::uint32_t> b;
    if (rank == r && mine.shown) {
      head = {1, mine.rect[0], mine.rect[1], mine.rect[2], mine.rect[3]};
      f = mine.linear, b = mine.rgba8;
    }
    if (r != 0) {
      if (rank == r) MPI_Send(head.data(), 5, MPI_INT, 0, 7, comm);
      if (rank == 0) MPI_Recv(head.data(), 5, MPI_INT, r, 7, comm, MPI_STATUS_IGNORE);
    }
    if (!head[0]) continue;
    const std::size_t n = static_cast<std::size_t>(head[3]) * head[4];
    if (r != 0) {
      if (rank == r) {
        if (blend)
          MPI_Send(f.data(), static_cast<int>(4 * n), MPI_FLOAT, 0, 8, comm);
        else
          MPI_Send(b.data(), static_cast<int>(n), MPI_UINT32_T, 0, 8, comm);
      }
      if (rank == 0) {
        if (blend) {
          f.resize(4 * n);
          MPI_Recv(f.data(), static_cast<int>(4 * n), MPI_FLOAT, r, 8, comm, MPI_STATUS_IGNORE);
        } else {
          b.resize(n);
          MPI_Recv(b.data(), static_cast<int>(n), MPI_UINT32_T, r, 8, comm, MPI_STATUS_IGNORE);
        }
      }
    }
    if (rank != 0) continue;
    for (int y = 0; y < head[4]; ++y)
      for (int x = 0; x < head[3]; ++x) {
        const std::size_t q = static_cast<std::size_t>(y) * head[3] + x;
        const std::size_t p = static_cast<std::size_t>(head[2] + y) * width + (head[1] + x);
        if (blend) {
          std::copy_n(&f[4 * q], 4, &out.linear[4 * p]);
          out.rgba8[p] = dfb::toneMapPixel(&f[4 * q], {});
        } else {
          out.rgba8[p] = b[q];
        }
      }
  }
  return out;
}

// The largest difference of two images per channel: linear floats when both have them, else
// RGBA8 levels; and how many pixels differ by more than `tolerance` in some channel.
Json compareImages(const Finished& a, const Finished& b, double tolerance) {
  double worst = 0;
  std::size_t over = 0;
  const bool linear = !a.linear.empty() && !b.linear.empty();
  const std::size_t pixels = a.rgba8.size();
  for (std::size_t p = 0; p < pixels; ++p) {
    double d = 0;
    for (int c = 0; c < 4; ++c) {
      const double x = linear ? a.linear[4 * p + c] : (a.rgba8[p] >> (8 * c)) & 0xFF;
      const double y = linear ? b.linear[4 * p + c] : (b.rgba8[p] >> (8 * c)) & 0xFF;
      d = std::max(d, std::abs(x - y));
    }
    worst = std::max(worst, d);
    if (d > tolerance) ++over;
  }
  return {{"units", linear ? "linear radiance" : "8-bit levels"},
          {"max_abs_diff", worst},
          {"tolerance", tolerance},
          {"pixels_over_tolerance", over},
          {"pixels", pixels}};
}

int compareFiles(const std::string& a, const std::string& b) {
  const wall::Image x = wall::readPng(a), y = wall::readPng(b);
  if (x.width != y.width || x.height != y.height) {
    std::printf("{\"error\": \"sizes differ: %dx%d vs %dx%d\"}\n", x.width, x.height, y.width,
                y.height);
    return 1;
  }
  Finished fa{x.pixels, {}}, fb{y.pixels, {}};
  std::printf("%s\n", compareImages(fa, fb, 2).dump().c_str());
  return 0;
}

int run(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--compare") return compareFiles(argv[2], argv[3]);
  messaging::MpiSession mpi(&argc, &argv);
  const int rank = mpi.worldRank(), ranks = mpi.worldSize();
  Options o;
  CLI::App cli{"DFB vs IceT sort-last compositing on the same bricks"};
  cli.add_option("--scene", o.scene, "scene (TOML or builtin:NAME)")->required();
  cli.add_option("--mode", o.mode, "transparent (ordered blending) or opaque (z-buffer)")
      ->check(CLI::IsMember({"transparent", "opaque"}));
  cli.add_option("--size", o.size, "canvas WxH");
  cli.add_option("--frames", o.frames, "measured frames (one more warms up)");
  cli.add_option("--orbit", o.orbit, "camera degrees per frame");
  cli.add_option("--threads", o.threads, "TBB threads per rank");
  cli.add_option("--tiles", o.tiles, "IceT tile grid, each tile shown by one rank");
  cli.add_option("--variants", o.variants, "comma-separated: dfb, icet-reduce, icet-radixk");
  cli.add_option("--images", o.images, "folder for the last frame's images (PNG)");
  cli.add_option("--seed", o.seed, "random seed");
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rank == 0 ? cli.exit(e) : 1;
  }
  int width = 0, height = 0, tilesX = 1, tilesY = 1;
  parseSize(o.size, width, height);
  parseSize(o.tiles, tilesX, tilesY);
  if (tilesX * tilesY > ranks) throw std::runtime_error("more tiles than ranks");
  const std::vector<std::string> variants = split(o.variants, ',');
  const bool blend = o.mode == "transparent";
  const bool tiled = tilesX * tilesY > 1;

  renderers::SceneDesc loaded = renderers::loadSceneDesc(o.scene);
  if (!blend) {
    // z-compositing keeps the nearest fragment and drops what lies behind it, so it is right only
    // for opaque surfaces: the opaque mode renders the scene's surfaces opaque and its volumes
    // not at all (the wavelet: both isosurfaces opaque, no haze).
    for (renderers::scivis::VolumeDesc& v : renderers::scivis::sciVisDesc(loaded).volumes)
      v.visible = false;
    for (renderers::Material& m : loaded.materials) m.opacity = 1.0f;
  }
  renderers::Environment& environment = loaded.environment;
  if (environment.kind != renderers::Environment::Kind::Constant) {
    // IceT blends one background colour under the image: both sides get the gradient's middle.
    environment.color = (environment.bottom + environment.top) * 0.5f;
    environment.kind = renderers::Environment::Kind::Constant;
    if (rank == 0)
      std::fprintf(stderr, "icet_bench: the scene's gradient background replaced by its middle\n");
  }
  const auto desc = std::make_shared<const renderers::SceneDesc>(std::move(loaded));
  renderers::RenderSettings settings;
  settings.width = width, settings.height = height, settings.seed = o.seed;

  // The DFB side: exactly the render ranks of `dfbwall --renderer scivis --bricks N`
  // (one brick per rank, no replication).
  MPI_Comm dfbComm, icetComm;
  MPI_Comm_dup(MPI_COMM_WORLD, &dfbComm);
  MPI_Comm_dup(MPI_COMM_WORLD, &icetComm);
  renderers::scivis::BrickDriverOptions bo;
  bo.threads = o.threads;
  renderers::scivis::BrickFrameDriver driver(
      desc, settings, bo, renderers::scivis::loadOwnBricks(*desc, ranks, 1, rank, ranks), dfbComm);
  messaging::Messenger messenger(dfbComm);
  dfb::DfbOptions options;
  options.width = width, options.height = height;
  options.format = blend ? dfb::DisplayFormat::RGBAF32 : dfb::DisplayFormat::RGBA8;
  options.compressGather = false;  // one host: dfbwall compresses only between hosts
  // Tiled: as dfbwall's route mode, nothing is gathered; every finished tile is tone-mapped on
  // its owner, cut at display borders and sent to the display's rank (ranks 0 .. tiles-1 here,
  // as IceT's tile displays are), which assembles its display.
  const wall::Layout layout = icetbench::tiledLayout(width, height, tilesX, tilesY);
  std::unique_ptr<icetbench::PieceReceiver> receiver;
  if (tiled) {
    options.format = dfb::DisplayFormat::NONE;
    if (rank < tilesX * tilesY) {
      receiver = std::make_unique<icetbench::PieceReceiver>(layout, rank, options.tileSize);
      messenger.registerObject(wall::kWallNodeObject, receiver.get());
    }
  }
  driver.configure(options);
  auto fb = std::make_unique<dfb::DistributedFrameBuffer>(messenger, dfbComm, options);
  if (tiled)
    fb->addPixelOp(std::make_shared<wall::DisplayRoutingOp>(
        messenger, layout, wall::RankRoles{0, tilesX * tilesY}, options.tileSize));

  // The IceT side: the same brick, rendered full-frame, composited afterwards.
  icetbench::BrickImage image(desc, settings, rank, ranks, !blend, options.toneMap);
  icetbench::IcetSetup setup;
  setup.blend = blend;
  setup.width = width, setup.height = height, setup.tilesX = tilesX, setup.tilesY = tilesY;
  const renderers::Vec3 bg = desc->environment.color;
  if (blend) {
    setup.background = {bg.x, bg.y, bg.z, 1.0f};
  } else {
    // IceT turns the colour into bytes by truncation: aim at the middle of the DFB's byte.
    const float px[4] = {bg.x, bg.y, bg.z, 1.0f};
    const std::uint32_t b = dfb::toneMapPixel(px, options.toneMap);
    for (int c = 0; c < 4; ++c)
      setup.background[static_cast<std::size_t>(c)] =
          (static_cast<float>((b >> (8 * c)) & 0xFF) + 0.5f) / 255.0f;
  }
  icetbench::IcetCompositor icet(icetComm, setup);

  std::vector<Finished> finished(variants.size());
  MPI_Barrier(MPI_COMM_WORLD);
  for (int f = 0; f <= o.frames; ++f) {
    const std::uint32_t id = static_cast<std::uint32_t>(f + 1);
    const dfb::FrameInfo frame{id, id};  // every frame its own epoch: a moving camera
    // As dfbwall --orbit: frame 1 shows the scene's camera, every frame turns it further.
    const renderers::CameraDesc camera = renderers::orbitCamera(
        desc->camera, static_cast<float>(std::fmod(double(o.orbit) * double(f), 360.0)));
    std::vector<int> order;
    for (int b : icetbench::visibilityOrder(driver.bricks(), camera.position))
      order.push_back(driver.tileBrickOwner(0, b));  // one holder per brick: its rank
    for (std::size_t k = 0; k < variants.size(); ++k) {
      const std::size_t v = (k + static_cast<std::size_t>(f)) % variants.size();
      const std::string& name = variants[v];
      Sample s{};
      if (receiver) receiver->expect(id);
      MPI_Barrier(MPI_COMM_WORLD);
      const auto t0 = Clock::now();
      s.start = ns(t0);
      double icetBytes = 0;
      if (name == "dfb") {
        const renderers::FrameReport report = driver.renderFrame(*fb, frame, camera);
        s.finished = ns(Clock::now());
        const std::int64_t last = fb->stats().lastSetTileNs;
        s.rendered = last != 0 ? last : s.start;
        s.renderMs = report.renderMs;
        s.display = tiled ? receiver != nullptr : rank == 0;
        // The display's last piece may come after this rank's end(): the image is finished then.
        if (receiver) s.finished = receiver->wait();
      } else if (name == "icet-reduce" || name == "icet-radixk") {
        image.render(frame, camera, driver);
        const auto t1 = Clock::now();
        s.rendered = ns(t1);
        s.renderMs = base::msBetween(t0, t1);
        icet.setStrategy(name == "icet-reduce" ? "reduce" : "radixk");
        const void* color = blend ? static_cast<const void*>(image.color().data())
                                  : static_cast<const void*>(image.rgba8().data());
        icet.composite(color, blend ? nullptr : image.depth().data(), image.viewport(), order);
        s.finished = ns(Clock::now());
        s.display = icet.displayedTile() >= 0;
        const icetbench::IcetTimes t = icet.times();
        icetBytes = t.bytesSent;
      } else {
        throw std::runtime_error("unknown variant '" + name + "'");
      }
      std::vector<Sample> all(static_cast<std::size_t>(rank == 0 ? ranks : 0));
      MPI_Gather(&s, sizeof s, MPI_BYTE, all.data(), sizeof s, MPI_BYTE, 0, MPI_COMM_WORLD);
      // IceT's own composite timer is not reported: it includes waiting for the slowest rank's
      // rendering (measured 80-1500 ms here), so it is no compositing overhead.
      double sumIcetBytes = 0;
      MPI_Reduce(&icetBytes, &sumIcetBytes, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
      if (rank == 0) {
        std::int64_t lastRender = 0, done = 0;
        double renderMs = 0;
        for (const Sample& r : all) {
          lastRender = std::max(lastRender, r.rendered);
          if (r.display) done = std::max(done, r.finished);
          renderMs = std::max(renderMs, r.renderMs);
        }
        Json line{{"frame", f},
                  {"warmup", f == 0},
                  {"variant", name},
                  {"ranks", ranks},
                  {"width", width},
                  {"height", height},
                  {"mode", o.mode},
                  {"tiles", o.tiles},
                  {"total_ms", static_cast<double>(done - all[0].start) * 1e-6},
                  {"render_ms", renderMs},
                  {"overhead_ms", static_cast<double>(done - lastRender) * 1e-6}};
        if (name != "dfb") {
          line["icet_bytes_sent"] = sumIcetBytes;
        }
        std::printf("%s\n", line.dump().c_str());
        std::fflush(stdout);
      }
      if (f == o.frames && !o.images.empty()) {
        if (name == "dfb" && tiled) {
          // The displays hold tone-mapped RGBA8, as a wall shows it.
          Part part;
          if (receiver) {
            const dfb::Region r = layout.displays[static_cast<std::size_t>(rank)].rect;
            part.shown = true, part.rect = {r.x0, r.y0, r.width(), r.height()};
            part.rgba8 = receiver->image().pixels;
          }
          finished[v] = assemble(part, false, width, height, MPI_COMM_WORLD);
        } else if (name == "dfb") {
          if (rank == 0) {
            finished[v].rgba8.resize(static_cast<std::size_t>(width) * height);
            if (blend) {
              finished[v].linear = fb->imageRgbaF32();
              for (std::size_t p = 0; p < finished[v].rgba8.size(); ++p)
                finished[v].rgba8[p] = dfb::toneMapPixel(&finished[v].linear[4 * p], {});
            } else {
              finished[v].rgba8 = fb->imageRgba8();
            }
          }
        } else {
          Part part;
          if (icet.displayedTile() >= 0) {
            part.shown = true, part.rect = icet.tileRect();
            if (blend)
              part.linear = icet.tileRgba();
            else
              part.rgba8 = icet.tileRgba8();
          }
          finished[v] = assemble(part, blend, width, height, MPI_COMM_WORLD);
        }
      }
    }
  }
  if (rank == 0 && !o.images.empty()) {
    const std::size_t dfbIndex = static_cast<std::size_t>(
        std::find(variants.begin(), variants.end(), "dfb") - variants.begin());
    for (std::size_t v = 0; v < variants.size(); ++v) {
      wall::writePng(o.images + "/" + variants[v] + ".png", finished[v].rgba8.data(), width,
                     height);
      if (v == dfbIndex || dfbIndex == variants.size()) continue;
      // Float summation order differs (IceT blends pairs of partial images, the DFB sorts each
      // pixel's fragments): a few ulps in linear radiance, at most a level in RGBA8.
      Json check{{"image_check",
                  compareImages(finished[dfbIndex], finished[v], blend && !tiled ? 1e-4 : 1)}};
      check["image_check"]["variant"] = variants[v];
      check["image_check"]["against"] = "dfb";
      std::printf("%s\n", check.dump().c_str());
    }
  }
  fb.reset();
  messenger.stop();
  MPI_Comm_free(&dfbComm);  // icetComm: IceT works on its own duplicate of it
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // scenes may have volumes, isosurfaces and particles
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "icet_bench: error: %s\n", e.what());
    // The session may have finalized MPI while unwinding: then exiting non-zero is enough.
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Abort(MPI_COMM_WORLD, 1);
    return 1;
  }
}
