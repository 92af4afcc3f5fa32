#include "apps/Stats.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <utility>

#include "base/Error.h"
#include "base/OutputFile.h"

namespace app {
namespace {

using Json = nlohmann::ordered_json;  // keys in the order written: lines read like the docs

constexpr double kBinRatio = 1.005;

// Each role reports its own stages only.
Json stagesOf(const RankTotals& t) {
  const StageTimes& s = t.stages;
  if (t.role > 0.5)
    return Json{{"piece_unpack", s.pieceUnpack},
                {"assemble", s.assemble},
                {"wall_wait", s.wallWait},
                {"upload", s.upload},
                {"draw", s.draw},
                {"barrier", s.barrier},
                {"present", s.present},
                {"process_cpu", s.processCpu},
                {"main_thread_cpu", s.mainThreadCpu},
                {"gl_threads_cpu", s.glThreadsCpu}};
  return Json{{"render", s.render},
              {"tile_unpack", s.tileUnpack},
              {"tile_operation", s.tileOperation},
              {"tone_map", s.toneMap},
              {"cut", s.cut},
              {"send", s.send},
              {"gather_relay", s.gatherRelay},
              {"render_cpu", s.renderCpu},
              {"process_cpu", s.processCpu}};
}

}  // namespace

LogHistogram::LogHistogram(double low, double high)
    : low_(low),
      logLow_(std::log(low)),
      step_(std::log(kBinRatio)),
      bins_(static_cast<size_t>(std::ceil(std::log(high / low) / std::log(kBinRatio))) + 1, 0) {}

void LogHistogram::add(double value) {
  if (std::isnan(value)) return;
  const double position = value <= low_ ? 0.0 : (std::log(value) - logLow_) / step_;
  const size_t bin = std::min(bins_.size() - 1, static_cast<size_t>(position));
  ++bins_[bin];
  ++count_;
}

double LogHistogram::centre(size_t bin) const {
  return std::exp(logLow_ + (static_cast<double>(bin) + 0.5) * step_);
}

double LogHistogram::median() const {
  if (count_ == 0) return 0;
  std::uint64_t seen = 0;
  for (size_t b = 0; b < bins_.size(); ++b) {
    seen += bins_[b];
    if (2 * seen >= count_) return centre(b);
  }
  return centre(bins_.size() - 1);
}

double LogHistogram::mad() const {
  if (count_ == 0) return 0;
  const double m = median();
  std::vector<std::pair<double, std::uint64_t>> deviations;
  for (size_t b = 0; b < bins_.size(); ++b)
    if (bins_[b]) deviations.emplace_back(std::abs(centre(b) - m), bins_[b]);
  std::sort(deviations.begin(), deviations.end());
  std::uint64_t seen = 0;
  for (const auto& [deviation, n] : deviations) {
    seen += n;
    if (2 * seen >= count_) return deviation;
  }
  return 0;
}

StatsStream::StatsStream(const std::string& path) : path_(path) {
  fd_ = base::openOutputFile(path, false).release();  // throws base::Error naming the path
}

StatsStream::~StatsStream() {
  if (fd_ >= 0) close(fd_);
}

void StatsStream::writeLine(const std::string& json) {
  const std::string line = json + "\n";
  // One write(2) per line: a reader (or a kill) never sees half a line unless the disk is full,
  // and a full disk is an error here.
  const ssize_t written = write(fd_, line.data(), line.size());
  if (written != static_cast<ssize_t>(line.size()))
    throw base::Error(path_ + ": cannot write the statistics: " +
                      (written < 0 ? std::strerror(errno) : "short write (disk full?)"));
}

void StatsStream::writeWallRoster(std::uint32_t version, std::uint32_t frame,
                                  const std::string& why,
                                  const std::vector<std::string>& lostDisplays) {
  writeLine(Json{{"wall_roster",
                  {{"version", version},
                   {"from_frame", frame},
                   {"why", why},
                   {"lost_displays", lostDisplays}}}}
                .dump());
}

void StatsStream::writeRun(const Job& job) {
  const Options& o = job.options;
  job_bricks_ = o.bricks;
  writeLine(Json{{"run",
                  {{"canvas", {job.canvasWidth, job.canvasHeight}},
                   {"mode", job.layout ? o.mode : "image"},
                   {"renderer", o.renderer},
                   {"render_ranks", job.roles.renderRanks},
                   {"wall_ranks", job.roles.wallRanks},
                   {"threads", o.threads},
                   {"orbit_degrees_per_frame", o.orbit},
                   {"spp", o.spp},
                   {"bricks", o.bricks},
                   {"replication", o.replication},
                   {"ghost", o.ghost},
                   {"frames_asked", o.frames},
                   {"frames_in_flight", o.framesInFlight},
                   {"max_spp", o.maxSpp},
                   {"control", !o.control.empty()}}}}
                .dump());
}

void StatsStream::writeFrame(const FrameRecord& f) {
  Json line{{"frame", f.frame},
            {"frame_ms", f.frameMs},
            {"render_ms", f.renderMs},
            {"composite_ms", f.compositeMs}};
  // Last setTile on any rank to the last display holding every piece of the frame.
  if (f.displaysCompleteNs > 0 && f.lastSetTileNs > 0) {
    const double ms = static_cast<double>(f.displaysCompleteNs - f.lastSetTileNs) * 1e-6;
    line["composite_to_displays_ms"] = ms;
    if (f.frameMs > 0) compositeShare_.add(std::max(0.0, ms) / f.frameMs);
  }
  line["rank0_pixel_bytes_received"] = f.rank0PixelBytes;
  line["wall_bytes_sent"] = f.wallBytesSent;
  line["wall_bytes_raw"] = f.wallBytesRaw;
  line["wall_pieces"] = f.wallPieces;
  line["wall_pieces_dropped"] = f.wallPiecesDropped;
  line["wall_pieces_to_other_hosts"] = f.wallPiecesToOtherHosts;
  line["wall_messages"] = f.wallMessages;
  line["messages_compressed"] = f.messagesCompressed;
  line["tile_bytes_sent"] = f.tileBytesSent;
  line["preview_bytes"] = f.previewBytes;
  line["tiles_rendered"] = f.tilesRendered;
  line["samples"] = f.samples;
  line["epoch"] = f.epoch;
  if (f.timeStep >= 0) line["time_step"] = f.timeStep;
  if (f.stepChanged)
    line["step"] = {{"read_ms", f.stepReadMs},
                    {"build_ms", f.stepBuildMs},
                    {"wait_ms", f.stepWaitMs},
                    {"switch_ms", f.stepSwitchMs}};
  if (f.requestId > 0) {
    // A steering request reached every display with this frame: how long after it arrived, and
    // how many frames the displays presented in between (this one included).
    line["request_id"] = f.requestId;
    if (f.displaysPresentedNs > 0) {
      const double ms = static_cast<double>(f.displaysPresentedNs - f.requestNs) * 1e-6;
      const std::int64_t frames = static_cast<std::int64_t>(f.frame) - f.presentedAtRequest;
      line["request_to_displays_ms"] = ms;
      line["request_to_displays_frames"] = frames;
      requestMs_.add(ms);
      maxRequestFrames_ = std::max(maxRequestFrames_, frames);
    }
  }
  writeLine(line.dump());
  frameMs_.add(f.frameMs);
  ++frames_;
}

void StatsStream::writeEnd(const std::vector<RankTotals>& ranks, bool stoppedEarly, int exitCode) {
  double peak[2] = {0, 0};
  for (size_t r = 0; r < ranks.size(); ++r) {
    const RankTotals& t = ranks[r];
    const int role = t.role > 0.5 ? 1 : 0;
    peak[role] = std::max(peak[role], t.peakRssKiB);
    Json line{{"rank", r},
              {"role", role ? "wall" : "render"},
              {"peak_rss_kib", t.peakRssKiB},
              {"stages_ms", stagesOf(t)}};
    if (!role) line["scene_bytes"] = t.sceneBytes;
    if (!role && t.isosurfaceTriangles + t.shadingOnlyTriangles > 0)
      line["isosurfaces"] = {{"camera_triangles", t.isosurfaceTriangles},
                             {"shading_only_triangles", t.shadingOnlyTriangles},
                             {"seconds", t.isosurfaceSeconds}};
    if (role && t.swapSpreadFrames > 0)
      line["swap_spread_ms"] = {{"max", t.swapSpreadMaxMs},
                                {"mean", t.swapSpreadSumMs / t.swapSpreadFrames}};
    if (!role && job_bricks_ > 0) {
      line["brick_tiles_rendered"] = t.brickTiles;
      line["brick_rays_skipped"] = t.brickRaysSkipped;
    }
    writeLine(line.dump());
  }
  const double medianMs = frameMs_.median();
  Json summary{{"frames", frames_},
               {"stopped_early", stoppedEarly},
               {"exit_code", exitCode},
               {"median_frame_ms", medianMs},
               {"mad_frame_ms", frameMs_.mad()},
               {"fps", medianMs > 0 ? 1000.0 / medianMs : 0.0},
               {"peak_rss_kib", {{"render", peak[0]}, {"wall", peak[1]}}}};
  if (requestMs_.count() > 0) {
    summary["requests_applied"] = requestMs_.count();
    summary["median_request_to_displays_ms"] = requestMs_.median();
    summary["max_request_to_displays_frames"] = maxRequestFrames_;
  }
  if (compositeShare_.count() > 0) {
    summary["median_composite_share"] = compositeShare_.median();
    summary["mad_composite_share"] = compositeShare_.mad();
  }
  writeLine(Json{{"summary", summary}}.dump());
}

}  // namespace app
