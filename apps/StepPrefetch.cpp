#include "apps/StepPrefetch.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include "base/Timing.h"

namespace app {

StepPrefetch::StepPrefetch(std::function<StepData(std::uint32_t step)> load)
    : load_(std::move(load)),
      flushZero_(_MM_GET_FLUSH_ZERO_MODE()),
      denormalsZero_(_MM_GET_DENORMALS_ZERO_MODE()) {}

StepPrefetch::~StepPrefetch() {
  if (pending_.valid()) pending_.wait();
}

void StepPrefetch::start(std::uint32_t step) {
  if (pending_.valid()) pending_.wait();  // a guess nobody took: dropped
  pendingStep_ = step;
  // Macrocells and isosurfaces are built in float: in the mode step 0 was built in, so a step
  // prefetched is the same bits as the step loaded alone.
  pending_ = std::async(std::launch::async, [this, step] {
    _MM_SET_FLUSH_ZERO_MODE(flushZero_);
    _MM_SET_DENORMALS_ZERO_MODE(denormalsZero_);
    return load_(step);
  });
}

StepData StepPrefetch::take(std::uint32_t step, double& waitedMs) {
  const auto began = base::Clock::now();
  if (!pending_.valid() || pendingStep_ != step) start(step);
  StepData data = pending_.get();
  pendingStep_.reset();
  waitedMs = base::msBetween(began, base::Clock::now());
  return data;
}

}  // namespace app
