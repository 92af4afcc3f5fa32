// Sort-last compositing over a per-tile dependency tree (paper 3.1.1).
//
// Generation 0 holds `expectedInputs` tiles (1: a single root); every tile announces `children`
// in the next generation, so generation g+1 expects the sum of the children announced in g. The
// tree is complete when each generation has exactly what the one before announced and the last
// announces none. Inputs come in any order — a child may arrive before its parent — so they are
// buffered, and blended only once the whole tree is here: per pixel, fragments sorted by depth
// (ties broken by generation, then sequence, so arrival order never matters) and composited
// front to back with premultiplied alpha.
#include <algorithm>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "base/Error.h"
#include "dfb/TileOperation.h"

namespace dfb {
namespace {

class AlphaBlendOperation final : public TileOperation {
 public:
  explicit AlphaBlendOperation(const Region& region) : region_(region) {
    finished_.reset(region, true);
  }

  void newFrame(const FrameInfo&, std::uint32_t, int expectedInputs) override {
    roots_ = std::max(1, expectedInputs);
    inputs_.clear();
    received_.clear();
    announced_.clear();
  }

  InputNeeds needs() const override { return {.tree = true}; }

  bool process(Tile&& input) override {
    received_[input.generation]++;
    announced_[input.generation] += input.children;
    inputs_.push_back(std::move(input));
    if (!treeComplete()) return false;
    blend();
    return true;
  }

  const Tile& finished() const override { return finished_; }
  // The caller's tile becomes the next frame's output buffer (blend() sizes it): a tile a frame
  // less to allocate, and none to copy.
  void exchangeFinished(Tile& other) override { std::swap(finished_, other); }

 private:
  std::string where() const {
    return "tile at (" + std::to_string(region_.x0) + ", " + std::to_string(region_.y0) + ")";
  }

  bool treeComplete() const {
    long expected = roots_;
    size_t total = 0;
    for (int g = 0;; ++g) {
      auto found = received_.find(g);
      const long got = found == received_.end() ? 0 : found->second;
      if (got > expected)
        throw base::Error(where() + ": generation " + std::to_string(g) + " got " +
                          std::to_string(got) + " tiles, but the generation before announced " +
                          std::to_string(expected));
      if (got < expected) return false;
      total += static_cast<size_t>(got);
      auto next = announced_.find(g);
      expected = next == announced_.end() ? 0 : next->second;
      if (expected == 0) break;
    }
    if (total != inputs_.size())
      throw base::Error(where() + ": tiles in generations beyond the end of the dependency tree");
    return true;
  }

  void blend() {
    // A fixed order of inputs first, so equal-depth fragments always blend the same way.
    std::vector<const Tile*> ordered;
    for (const Tile& t : inputs_) ordered.push_back(&t);
    std::stable_sort(ordered.begin(), ordered.end(), [](const Tile* a, const Tile* b) {
      return a->generation != b->generation ? a->generation < b->generation
                                            : a->sequence < b->sequence;
    });
    const size_t n = static_cast<size_t>(region_.pixelCount());
    const float infinity = std::numeric_limits<float>::infinity();
    // Every pixel's colour and depth is written below: sized, not cleared (exchangeFinished()
    // may have handed in any tile).
    finished_.region = region_;
    finished_.generation = finished_.children = 0;
    finished_.accumulationId = finished_.sequence = 0;
    finished_.weight = finished_.samples = 1;
    finished_.color.resize(4 * n);
    finished_.depth.resize(n);
    finished_.normal.clear(), finished_.albedo.clear(), finished_.rgba8.clear();
    std::uint32_t samples = 1;
    for (const Tile* t : ordered) samples = std::max(samples, t->samples);
    for (const Tile* t : ordered)
      if (t->samples != 1 && t->samples != samples)
        throw base::Error(where() + ": a tile of " + std::to_string(t->samples) +
                          " samples in a tree of " + std::to_string(samples) +
                          " (every tile carries that many, or 1)");
    if (samples > 1) return blendSamples(ordered, samples);
    if (ordered.size() == 1) return blendOne(*ordered[0]);
    if (ordered.size() == 2) return blendTwo(*ordered[0], *ordered[1]);
    std::vector<std::pair<float, const Tile*>> fragments(ordered.size());
    for (size_t p = 0; p < n; ++p) {
      for (size_t i = 0; i < ordered.size(); ++i)
        fragments[i] = {ordered[i]->depth.empty() ? infinity : ordered[i]->depth[p], ordered[i]};
      // A stable sort of a handful (one per brick the tile needs): insertion is the cheapest
      // and orders exactly as std::stable_sort does.
      for (size_t i = 1; i < fragments.size(); ++i) {
        const std::pair<float, const Tile*> f = fragments[i];
        size_t j = i;
        for (; j > 0 && f.first < fragments[j - 1].first; --j) fragments[j] = fragments[j - 1];
        fragments[j] = f;
      }
      float out[4] = {0, 0, 0, 0};
      for (const auto& [depth, tile] : fragments) {
        const float* c = &tile->color[4 * p];
        const float transmitted = 1.0f - out[3];
        for (int k = 0; k < 4; ++k) out[k] += transmitted * c[k];
      }
      for (int k = 0; k < 4; ++k) finished_.color[4 * p + static_cast<size_t>(k)] = out[k];
      finished_.depth[p] = fragments.empty() ? infinity : fragments.front().first;
    }
  }

  // blend() of tiles that carry `samples` samples apart (or 1, standing for every sample): each
  // sample's fragments composited as blend() composites a pixel (two tiles: blendPixelPair, as
  // blendTwo), then their mean; the depth is sample 0's.
  void blendSamples(const std::vector<const Tile*>& ordered, std::uint32_t samples) {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    const float infinity = std::numeric_limits<float>::infinity();
    auto at = [n](const Tile& t, std::uint32_t s, size_t p) {
      return (t.samples == 1 ? 0 : static_cast<size_t>(s) * n) + p;
    };
    auto depthOf = [&](const Tile& t, std::uint32_t s, size_t p) {
      return t.depth.empty() ? infinity : t.depth[at(t, s, p)];
    };
    std::vector<float> composites(4 * static_cast<size_t>(samples));
    std::vector<std::pair<float, const Tile*>> fragments(ordered.size());
    for (size_t p = 0; p < n; ++p) {
      float front = infinity;
      for (std::uint32_t s = 0; s < samples; ++s) {
        float* out = &composites[4 * s];
        if (ordered.size() == 2) {
          const Tile &a = *ordered[0], &b = *ordered[1];
          const float d = blendPixelPair(&a.color[4 * at(a, s, p)], depthOf(a, s, p),
                                         &b.color[4 * at(b, s, p)], depthOf(b, s, p), out);
          if (s == 0) front = d;
          continue;
        }
        for (size_t i = 0; i < ordered.size(); ++i)
          fragments[i] = {depthOf(*ordered[i], s, p), ordered[i]};
        for (size_t i = 1; i < fragments.size(); ++i) {  // insertion, as blend()
          const std::pair<float, const Tile*> f = fragments[i];
          size_t j = i;
          for (; j > 0 && f.first < fragments[j - 1].first; --j) fragments[j] = fragments[j - 1];
          fragments[j] = f;
        }
        for (int k = 0; k < 4; ++k) out[k] = 0;
        for (const auto& [depth, tile] : fragments) {
          const float* c = &tile->color[4 * at(*tile, s, p)];
          const float transmitted = 1.0f - out[3];
          for (int k = 0; k < 4; ++k) out[k] += transmitted * c[k];
        }
        if (s == 0) front = fragments.front().first;
      }
      meanOfComposites(composites.data(), samples, &finished_.color[4 * p]);
      finished_.depth[p] = front;
    }
  }

  // blend() of a lone tile (a root without children: a tile with one brick whose renderer
  // blended the background in itself), the same operations: each value added to 0.
  void blendOne(const Tile& a) {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    const float infinity = std::numeric_limits<float>::infinity();
    for (size_t i = 0; i < 4 * n; ++i) finished_.color[i] = 0.0f + 1.0f * a.color[i];
    if (a.depth.empty())
      std::fill(finished_.depth.begin(), finished_.depth.end(), infinity);
    else
      std::copy(a.depth.begin(), a.depth.end(), finished_.depth.begin());
  }

  // blend() of two tiles in that order (the common tree: the background and one brick),
  // blendPixelPair's operations, without the per-pixel fragment list and sort.
  void blendTwo(const Tile& a, const Tile& b) {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    const float infinity = std::numeric_limits<float>::infinity();
    for (size_t p = 0; p < n; ++p)
      finished_.depth[p] =
          blendPixelPair(&a.color[4 * p], a.depth.empty() ? infinity : a.depth[p], &b.color[4 * p],
                         b.depth.empty() ? infinity : b.depth[p], &finished_.color[4 * p]);
  }

  Region region_;
  int roots_ = 1;
  std::vector<Tile> inputs_;
  std::map<int, long> received_, announced_;
  Tile finished_;
};

}  // namespace

TileOperationFactory alphaBlendOperation() {
  return [](const Region& region) { return std::make_unique<AlphaBlendOperation>(region); };
}

}  // namespace dfb
