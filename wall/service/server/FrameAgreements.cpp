#include "wall/service/server/FrameAgreements.h"

#include <algorithm>

namespace wall::service {
namespace {
// Members' pixels of frames the head never asks for (it gave them up) do not pile up.
constexpr std::size_t kMaxGathers = 8;
}  // namespace

void FrameAgreements::clear() {
  barriers_.clear();
  gathers_.clear();
  pacedUpTo_.reset();
}

bool FrameAgreements::arrive(int process, std::uint32_t frameId,
                             const std::vector<std::int64_t>& values, Clock::time_point now,
                             bool paces) {
  auto [at, fresh] = barriers_.try_emplace(frameId);
  Barrier& b = at->second;
  if (fresh) {
    b.values = values;
    b.arrived.assign(static_cast<size_t>(processCount_), false);
  } else {
    if (values.size() != b.values.size()) return false;
    for (size_t i = 0; i < values.size(); ++i) b.values[i] = std::max(b.values[i], values[i]);
  }
  b.arrived[static_cast<size_t>(process)] = true;
  if (paces) {
    // The job is at this frame: it and every earlier barrier are frames it rendered.
    pacedUpTo_ = std::max(pacedUpTo_.value_or(0), frameId);
    for (auto& [frame, earlier] : barriers_) {
      if (frame > frameId) break;
      if (!earlier.opened) earlier.opened = now;
    }
  }
  return true;
}

std::vector<FrameAgreements::Release> FrameAgreements::complete(const TakesPart& takesPart,
                                                                const GoesUnpaced& goesUnpaced) {
  std::vector<Release> out;
  for (auto at = barriers_.begin(); at != barriers_.end();) {
    const std::uint32_t frameId = at->first;
    Barrier& b = at->second;
    bool all = (pacedUpTo_ && frameId <= *pacedUpTo_) || (goesUnpaced && goesUnpaced(frameId));
    for (int p = 0; p < processCount_ && all; ++p)
      all = !takesPart(p, frameId) || b.arrived[static_cast<size_t>(p)];
    if (!all) {
      ++at;
      continue;
    }
    Release r{frameId, std::move(b.values), {}};
    for (int p = 0; p < processCount_; ++p)
      if (b.arrived[static_cast<size_t>(p)]) r.processes.push_back(p);
    out.push_back(std::move(r));
    at = barriers_.erase(at);
  }
  return out;
}

std::vector<FrameAgreements::Overdue> FrameAgreements::overdue(
    const TakesPart& takesPart, Clock::time_point openedBefore) const {
  std::vector<Overdue> out;
  for (const auto& [frameId, b] : barriers_) {
    if (!b.opened || *b.opened >= openedBefore) continue;
    Overdue o{frameId, {}};
    for (int p = 0; p < processCount_; ++p)
      if (takesPart(p, frameId) && !b.arrived[static_cast<size_t>(p)]) o.missing.push_back(p);
    if (!o.missing.empty()) out.push_back(std::move(o));
  }
  return out;
}

FrameAgreements::Gather& FrameAgreements::gatherOf(std::uint32_t frameId) {
  auto [at, fresh] = gathers_.try_emplace(frameId);
  if (fresh) {
    at->second.pixels.resize(static_cast<size_t>(processCount_));
    at->second.got.assign(static_cast<size_t>(processCount_), false);
  }
  while (gathers_.size() > kMaxGathers && !gathers_.begin()->second.headAsked)
    gathers_.erase(gathers_.begin());
  return gathers_.at(frameId);
}

void FrameAgreements::pixels(int process, std::uint32_t frameId,
                             std::vector<std::uint32_t> pixels) {
  Gather& g = gatherOf(frameId);
  g.pixels[static_cast<size_t>(process)] = std::move(pixels);
  g.got[static_cast<size_t>(process)] = true;
}

void FrameAgreements::headPixels(std::uint32_t frameId, std::vector<std::uint32_t> pixels,
                                 Clock::time_point deadline) {
  Gather& g = gatherOf(frameId);
  g.pixels[0] = std::move(pixels);
  g.got[0] = true;
  g.headAsked = true;
  g.deadline = deadline;
}

std::vector<FrameAgreements::Gathered> FrameAgreements::gathered(const TakesPart& takesPart,
                                                                 Clock::time_point now) {
  std::vector<Gathered> out;
  for (auto at = gathers_.begin(); at != gathers_.end();) {
    Gather& g = at->second;
    bool complete = g.headAsked;
    if (complete && now < g.deadline)
      for (int p = 0; p < processCount_ && complete; ++p)
        complete = !takesPart(p, at->first) || g.got[static_cast<size_t>(p)];
    if (!complete) {
      ++at;
      continue;
    }
    out.push_back({at->first, std::move(g.pixels)});
    at = gathers_.erase(at);
  }
  return out;
}

}  // namespace wall::service
