#include "base/Parallel.h"

#include <pmmintrin.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include <optional>

namespace base {

struct ThreadLimit::Impl {
  std::optional<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int threads) : impl_(std::make_unique<Impl>()) {
  if (threads > 0)
    impl_->control.emplace(tbb::global_control::max_allowed_parallelism,
                           static_cast<std::size_t>(threads));
}

ThreadLimit::~ThreadLimit() = default;

struct TaskArena::Impl {
  tbb::task_arena arena;
  explicit Impl(int threads) : arena(threads > 0 ? threads : tbb::task_arena::automatic) {}
};

TaskArena::TaskArena(int threads) : impl_(std::make_unique<Impl>(threads)) {
  // An arena takes the floating-point settings of the thread that initialises it and applies
  // them to each of its tasks (and to a thread while it is inside execute()).
  FloatModeGuard caller;
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  impl_->arena.initialize();
}

TaskArena::~TaskArena() = default;

void TaskArena::execute(const std::function<void()>& work) { impl_->arena.execute(work); }

FloatModeGuard::FloatModeGuard()
    : flushZero_(_MM_GET_FLUSH_ZERO_MODE()), denormalsZero_(_MM_GET_DENORMALS_ZERO_MODE()) {}

FloatModeGuard::~FloatModeGuard() {
  _MM_SET_FLUSH_ZERO_MODE(flushZero_);
  _MM_SET_DENORMALS_ZERO_MODE(denormalsZero_);
}

void parallelFor(std::size_t count, const std::function<void(std::size_t)>& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                    });
}

void parallelSort(std::vector<std::uint64_t>& values) {
  tbb::parallel_sort(values.begin(), values.end());
}

}  // namespace base
