#include "renderers/WorkDistribution.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "base/Error.h"

namespace renderers {

Distribution distributionFromName(const std::string& name) {
  if (name == "static") return Distribution::Static;
  if (name == "roundrobin") return Distribution::RoundRobin;
  if (name == "dynamic") return Distribution::Dynamic;
  throw base::Error("unknown work distribution '" + name +
                    "' (choose static, roundrobin or dynamic)");
}

WorkPlan planWork(int tileCount, int ranks, std::uint32_t spp, std::span<const float> errors,
                  Distribution distribution, const DynamicOptions& dynamic) {
  if (tileCount < 0 || ranks <= 0) throw base::Error("work distribution: need at least one rank");
  WorkPlan plan;
  plan.perRank.resize(static_cast<std::size_t>(ranks));
  plan.inputsPerTile.assign(static_cast<std::size_t>(tileCount), 1);
  std::vector<int> primary(static_cast<std::size_t>(tileCount));
  for (int t = 0; t < tileCount; ++t) {
    primary[t] = distribution == Distribution::Static
                     ? static_cast<int>(static_cast<long long>(t) * ranks / tileCount)
                     : t % ranks;
    plan.perRank[primary[t]].push_back({t, 0, spp});
  }
  if (distribution != Distribution::Dynamic || ranks < 2 ||
      errors.size() != static_cast<std::size_t>(tileCount))
    return plan;

  const float maxError = errors.empty() ? 0.0f : *std::max_element(errors.begin(), errors.end());
  if (!(maxError > 0)) return plan;
  // Worst tiles first; ties broken by index so every rank computes the same plan.
  std::vector<int> order(static_cast<std::size_t>(tileCount));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return errors[a] > errors[b]; });
  const int maxInputs = std::min(dynamic.maxInputs, ranks);
  const int chosen = static_cast<int>(dynamic.fraction * static_cast<float>(tileCount));

  std::vector<std::uint64_t> load(static_cast<std::size_t>(ranks), 0);
  for (int r = 0; r < ranks; ++r) load[r] = plan.perRank[r].size() * std::uint64_t{spp};
  for (int k = 0; k < chosen; ++k) {
    const int t = order[k];
    if (!(errors[t] > 0)) break;
    // Extra inputs in proportion to how far the error is above zero, relative to the worst.
    const int inputs =
        1 + static_cast<int>(std::ceil(static_cast<float>(maxInputs - 1) * errors[t] / maxError));
    std::vector<bool> has(static_cast<std::size_t>(ranks), false);
    has[primary[t]] = true;
    for (int j = 1; j < std::min(inputs, maxInputs); ++j) {
      int best = -1;
      for (int r = 0; r < ranks; ++r)
        if (!has[r] && (best < 0 || load[r] < load[best])) best = r;
      has[best] = true;
      load[best] += spp;
      plan.perRank[best].push_back({t, static_cast<std::uint32_t>(j) * spp, spp});
      ++plan.inputsPerTile[t];
    }
  }
  return plan;
}

}  // namespace renderers
