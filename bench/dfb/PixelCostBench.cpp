// CPU per delivered pixel of the delivery pipeline, stage by stage, on one thread: what a tile
// costs after rendering and before the wire on its owner (tile operation, tone mapping, cutting
// into display pieces, sealing the message: plane-delta filter and Snappy when it leaves the
// host), and after the wire on the wall (opening the message: Snappy, reading the piece header,
// copying it into the display image: plane-delta decode). MPI's own copies and GL are not in it.
//
// It runs the library's own functions on every tile of a wall (default: the benchmarks' 2x2
// 1080p wall, 64-pixel tiles) for a few frames and reads the thread's CPU clock
// (CLOCK_THREAD_CPUTIME_ID) between stages, so time the thread spends preempted by other
// processes does not count (the elapsed-time timers this replaces read 5-10x high on a loaded
// machine). The clock's own cost is measured and subtracted. Each stage is also a function of its
// own (stage*), so `valgrind --tool=callgrind --collect-atstart=no --toggle-collect='stage*'`
// counts its instructions repeatably (bench/cluster.sh does).
//
// Contents: "pattern" is the pattern renderer's display pixels (RGBA8, the write operation, no
// tone mapping); "float-noisy" is linear float RGBA as the path tracer gives it at 1 spp (the
// pattern's colours times per-pixel noise), accumulated and tone-mapped. Links: "same-host"
// (nothing compressed, as the messenger does within a host) and "other-host" (plane-delta +
// Snappy). Prints a table and writes JSON (--json PATH).
//
//   pixel_cost_bench [--wall LAYOUT.toml] [--frames N] [--content pattern|float-noisy|all]
//                    [--link same-host|other-host|all] [--json PATH]

#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "base/Timing.h"
#include "dfb/PixelOp.h"
#include "dfb/TileOperation.h"
#include "dfb/ToneMapKernel.h"
#include "messaging/Envelope.h"
#include "renderers/PatternRenderer.h"
#include "wall/layout/Layout.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace {

// One input tile per canvas tile, made once (rendering is not what is measured).
std::vector<dfb::Tile> makeInputs(const dfb::TileGrid& grid, bool floatNoisy) {
  renderers::RenderSettings settings;
  settings.width = grid.width();
  settings.height = grid.height();
  if (!floatNoisy) settings.displayPixels = dfb::ToneMapSettings{};
  renderers::PatternRenderer pattern(settings);
  pattern.beginFrame(dfb::FrameInfo{1, 1}, renderers::CameraDesc{});
  std::vector<dfb::Tile> tiles(static_cast<size_t>(grid.tileCount()));
  std::uint32_t state = 12345;
  for (int t = 0; t < grid.tileCount(); ++t) {
    dfb::Tile& tile = tiles[static_cast<size_t>(t)];
    pattern.render(grid.region(t), 0, 0, 1, tile);
    if (!floatNoisy) continue;
    for (size_t i = 0; i < tile.color.size(); ++i) {
      if (i % 4 == 3) continue;
      state = state * 1664525u + 1013904223u;  // a 1-spp path tracer's spread: 0 .. ~3x
      tile.color[i] *= 3.0f * static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
    }
  }
  return tiles;
}

// The stages, kept out of line so callgrind can count each (see the file comment).
[[gnu::noinline]] const dfb::Tile& stageTileOperation(dfb::TileOperation& op, dfb::Tile&& input) {
  op.process(std::move(input));
  return op.finished();
}

[[gnu::noinline]] void stageToneMap(dfb::ToneMapOp& toneMap, dfb::TileOperation& op,
                                    dfb::FinishedTile& finished,
                                    std::vector<std::uint32_t>& rgba8) {
  // As DistributedFrameBuffer::finishTile: display pixels are taken as they came.
  if (finished.linear->rgba8.size() == static_cast<size_t>(finished.region.pixelCount()))
    rgba8 = op.takeDisplayPixels();
  else
    toneMap.process(finished);
}

[[gnu::noinline]] messaging::Bytes stageCut(std::uint32_t frame, const wall::Piece& piece,
                                            const dfb::FinishedTile& tile, bool planeDelta) {
  return wall::packPiece(frame, piece.display, piece.local, tile.rgba8->data(), tile.region.width(),
                         piece.canvas.x0 - tile.region.x0, piece.canvas.y0 - tile.region.y0,
                         planeDelta);
}

[[gnu::noinline]] messaging::Bytes stageSeal(messaging::Bytes&& piece, bool compress) {
  // The messenger compresses payloads of 2048 bytes or more that leave the host.
  const bool large = piece.size() >= 2048;  // read before the payload moves
  return messaging::sealEnvelope(std::move(piece), wall::kWallNodeObject, compress && large);
}

[[gnu::noinline]] void stageOpen(messaging::Bytes&& wire, messaging::Bytes& payload) {
  messaging::openEnvelope(std::move(wire), std::size_t{1} << 30, payload);
}

[[gnu::noinline]] wall::PieceHeader stagePieceUnpack(const messaging::Bytes& payload) {
  return wall::readPieceHeader(payload);
}

[[gnu::noinline]] void stageAssemble(const messaging::Bytes& payload,
                                     const wall::PieceHeader& header, wall::Image& display) {
  wall::copyPiece(payload, header, display);
}

const char* const kRenderStages[] = {"tile_operation", "tone_map", "cut", "seal"};
const char* const kWallStages[] = {"open", "piece_unpack", "assemble"};

struct Result {
  std::string content, link;
  std::map<std::string, double> ns;  // stage -> ns per delivered pixel
  double renderTotal = 0, wallTotal = 0, wireBytesPerPixel = 0;
};

Result run(const wall::Layout& layout, int tileSize, int frames, bool floatNoisy, bool otherHost,
           double clockNs) {
  const dfb::TileGrid grid(layout.canvasWidth, layout.canvasHeight, tileSize);
  const std::vector<dfb::Tile> inputs = makeInputs(grid, floatNoisy);
  std::vector<std::vector<wall::Piece>> pieces(static_cast<size_t>(grid.tileCount()));
  for (int t = 0; t < grid.tileCount(); ++t)
    pieces[static_cast<size_t>(t)] = wall::piecesOf(layout, grid.region(t));
  std::vector<wall::Image> displays;
  std::uint64_t delivered = 0;
  for (const wall::Display& d : layout.displays) {
    displays.emplace_back(d.rect.width(), d.rect.height());
    delivered += static_cast<std::uint64_t>(d.rect.pixelCount());
  }
  const dfb::TileOperationFactory factory =
      floatNoisy ? dfb::accumulateOperation() : dfb::writeOperation();
  std::vector<std::unique_ptr<dfb::TileOperation>> ops;
  std::vector<std::vector<std::uint32_t>> rgba8(static_cast<size_t>(grid.tileCount()));
  for (int t = 0; t < grid.tileCount(); ++t) ops.push_back(factory(grid.region(t)));
  dfb::ToneMapOp toneMap;

  std::map<std::string, std::int64_t> ns;
  std::uint64_t wire = 0;
  messaging::Bytes payload;
  // Frame 0 warms caches and allocations up and is not counted.
  for (int frame = 0; frame <= frames; ++frame) {
    const bool counted = frame > 0;
    std::map<std::string, std::int64_t> frameNs;
    for (int t = 0; t < grid.tileCount(); ++t) {
      if (pieces[static_cast<size_t>(t)].empty()) continue;  // behind bezels: never rendered
      dfb::Tile input = inputs[static_cast<size_t>(t)];      // the renderer's output (untimed)
      dfb::TileOperation& op = *ops[static_cast<size_t>(t)];
      op.newFrame(dfb::FrameInfo{static_cast<std::uint32_t>(frame + 1),
                                 static_cast<std::uint32_t>(frame + 1)},
                  0, 1);
      std::int64_t a = base::threadCpuNs();
      const dfb::Tile& finishedTile = stageTileOperation(op, std::move(input));
      std::int64_t b = base::threadCpuNs();
      frameNs["tile_operation"] += b - a;
      dfb::FinishedTile finished;
      finished.tileIndex = t;
      finished.region = grid.region(t);
      finished.frameId = static_cast<std::uint32_t>(frame + 1);
      finished.linear = &finishedTile;
      finished.rgba8 = &rgba8[static_cast<size_t>(t)];
      a = base::threadCpuNs();
      stageToneMap(toneMap, op, finished, rgba8[static_cast<size_t>(t)]);
      b = base::threadCpuNs();
      frameNs["tone_map"] += b - a;
      for (const wall::Piece& piece : pieces[static_cast<size_t>(t)]) {
        a = base::threadCpuNs();
        messaging::Bytes bytes = stageCut(finished.frameId, piece, finished, otherHost);
        b = base::threadCpuNs();
        messaging::Bytes sealed = stageSeal(std::move(bytes), otherHost);
        const std::int64_t c = base::threadCpuNs();
        if (counted) wire += sealed.size();
        // The wire: MPI moves the bytes (not measured here).
        stageOpen(std::move(sealed), payload);
        const std::int64_t d = base::threadCpuNs();
        const wall::PieceHeader header = stagePieceUnpack(payload);
        const std::int64_t e = base::threadCpuNs();
        stageAssemble(payload, header, displays[static_cast<size_t>(header.display)]);
        const std::int64_t f = base::threadCpuNs();
        frameNs["cut"] += b - a;
        frameNs["seal"] += c - b;
        frameNs["open"] += d - c;
        frameNs["piece_unpack"] += e - d;
        frameNs["assemble"] += f - e;
      }
    }
    if (counted)
      for (const auto& [stage, v] : frameNs) ns[stage] += v;
  }
  Result r;
  r.content = floatNoisy ? "float-noisy" : "pattern";
  r.link = otherHost ? "other-host" : "same-host";
  const double pixels = static_cast<double>(delivered) * frames;
  // Every stage span carries one clock read's cost.
  std::map<std::string, double> spans;  // clock spans per stage over the counted frames
  const int tiles = [&] {
    int n = 0;
    for (const auto& p : pieces) n += !p.empty();
    return n;
  }();
  int pieceCount = 0;
  for (const auto& p : pieces) pieceCount += static_cast<int>(p.size());
  spans["tile_operation"] = spans["tone_map"] = static_cast<double>(tiles) * frames;
  for (const char* s : {"cut", "seal", "open", "piece_unpack", "assemble"})
    spans[s] = static_cast<double>(pieceCount) * frames;
  for (const char* s : kRenderStages) {
    const double v = std::max(0.0, (static_cast<double>(ns[s]) - spans[s] * clockNs) / pixels);
    r.ns[s] = v;
    r.renderTotal += v;
  }
  for (const char* s : kWallStages) {
    const double v = std::max(0.0, (static_cast<double>(ns[s]) - spans[s] * clockNs) / pixels);
    r.ns[s] = v;
    r.wallTotal += v;
  }
  r.wireBytesPerPixel = static_cast<double>(wire) / pixels;
  return r;
}

// The tone-mapping kernels alone on one noisy 64x64 float tile, over and over (cache-resident):
// ns per pixel of the scalar kernel and of the AVX2 one (0 where the CPU has none).
std::pair<double, double> toneMapKernelsNs() {
  const dfb::TileGrid grid(64, 64, 64);
  const std::vector<dfb::Tile> tile = makeInputs(grid, true);
  const std::vector<float>& rgba = tile.front().color;
  std::vector<std::uint32_t> out(4096);
  constexpr int kRepeats = 2000;
  const auto time = [&](auto kernel) {
    const std::int64_t start = base::threadCpuNs();
    for (int i = 0; i < kRepeats; ++i) kernel(rgba.data(), out.size(), out.data(), {});
    return static_cast<double>(base::threadCpuNs() - start) / (kRepeats * 4096.0);
  };
  const double scalar = time(dfb::toneMapPixelsScalar);
  return {scalar, dfb::toneMapAvx2Available() ? time(dfb::toneMapPixelsAvx2) : 0.0};
}

// The cost of one clock read, subtracted from every span (each span holds one).
double clockReadNs() {
  constexpr int kReads = 200000;
  const std::int64_t start = base::threadCpuNs();
  std::int64_t sink = 0;
  for (int i = 0; i < kReads; ++i) sink += base::threadCpuNs() & 1;
  const std::int64_t end = base::threadCpuNs();
  return static_cast<double>(end - start - (sink < 0 ? 1 : 0)) / kReads;
}

}  // namespace

int main(int argc, char** argv) {
  std::string wallFile = DFBWALL_SOURCE_DIR "/configs/walls/2x2-1080p.toml";
  std::string json, content = "all", link = "all";
  int frames = 5, tileSize = 64;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (a == "--wall" && hasValue)
      wallFile = argv[++i];
    else if (a == "--frames" && hasValue)
      frames = std::stoi(argv[++i]);
    else if (a == "--tile-size" && hasValue)
      tileSize = std::stoi(argv[++i]);
    else if (a == "--content" && hasValue)
      content = argv[++i];
    else if (a == "--link" && hasValue)
      link = argv[++i];
    else if (a == "--json" && hasValue)
      json = argv[++i];
    else {
      std::fprintf(stderr, "pixel_cost_bench: unknown argument '%s' (see the source's header)\n",
                   a.c_str());
      return 2;
    }
  }
  if (frames < 1 || tileSize < 1) {
    std::fprintf(stderr, "pixel_cost_bench: --frames and --tile-size must be positive\n");
    return 2;
  }
  const wall::Layout layout = wall::loadLayout(wallFile);
  const double clockNs = clockReadNs();
  const auto [toneScalar, toneAvx2] = toneMapKernelsNs();
  std::vector<Result> results;
  for (const bool floatNoisy : {false, true}) {
    if (content != "all" && content != (floatNoisy ? "float-noisy" : "pattern")) continue;
    for (const bool otherHost : {false, true}) {
      if (link != "all" && link != (otherHost ? "other-host" : "same-host")) continue;
      results.push_back(run(layout, tileSize, frames, floatNoisy, otherHost, clockNs));
    }
  }
  std::printf(
      "CPU ns per delivered pixel, one thread, %s (%dx%d canvas, tiles of %d), %d frames;"
      " clock read %.0f ns subtracted per span\n",
      wallFile.c_str(), layout.canvasWidth, layout.canvasHeight, tileSize, frames, clockNs);
  std::string rows;
  for (const Result& r : results) {
    std::printf("  %-11s %-10s render %.3f (", r.content.c_str(), r.link.c_str(), r.renderTotal);
    for (const char* s : kRenderStages) std::printf(" %s %.3f", s, r.ns.at(s));
    std::printf(" )  wall %.3f (", r.wallTotal);
    for (const char* s : kWallStages) std::printf(" %s %.3f", s, r.ns.at(s));
    std::printf(" )  wire %.3f B/px\n", r.wireBytesPerPixel);
    char buffer[1024];
    std::string stages;
    for (const auto& [s, v] : r.ns) {
      std::snprintf(buffer, sizeof buffer, "%s\"%s\": %.4f", stages.empty() ? "" : ", ", s.c_str(),
                    v);
      stages += buffer;
    }
    std::snprintf(buffer, sizeof buffer,
                  "%s\n    {\"content\": \"%s\", \"link\": \"%s\", \"render_total\": %.4f, "
                  "\"wall_total\": %.4f, \"wire_bytes_per_pixel\": %.4f, \"stages\": {",
                  rows.empty() ? "" : ",", r.content.c_str(), r.link.c_str(), r.renderTotal,
                  r.wallTotal, r.wireBytesPerPixel);
    rows += buffer;
    rows += stages + "}}";
  }
  std::printf("  tone-mapping kernels on a cache-resident tile: scalar %.3f, AVX2 %.3f ns/pixel\n",
              toneScalar, toneAvx2);
  if (!json.empty()) {
    std::ofstream out(json);
    out << "{\"figure\": \"pixel_cost\", \"unit\": \"CPU ns per delivered pixel, one thread\","
        << " \"wall\": \"" << wallFile << "\", \"canvas\": [" << layout.canvasWidth << ", "
        << layout.canvasHeight << "], \"tile_size\": " << tileSize << ", \"frames\": " << frames
        << ", \"clock_read_ns\": " << clockNs
        << ",\n \"tone_map_kernel_ns_per_pixel\": {\"scalar\": " << toneScalar
        << ", \"avx2\": " << toneAvx2 << "}"
        << ",\n \"render_stages\": [\"tile_operation\", \"tone_map\", \"cut\", \"seal\"],"
        << " \"wall_stages\": [\"open\", \"piece_unpack\", \"assemble\"],\n \"results\": [" << rows
        << "\n ]}\n";
    if (!out) {
      std::fprintf(stderr, "pixel_cost_bench: cannot write %s\n", json.c_str());
      return 1;
    }
  }
  return 0;
}
