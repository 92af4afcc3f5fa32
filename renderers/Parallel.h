#pragma once
// All TBB use of the renderers, behind two names.
#include <cstddef>
#include <functional>
#include <memory>

namespace renderers {

// Caps the worker threads of the whole process while it lives (tbb::global_control);
// threads <= 0 leaves TBB's default. Nest or overlap them only with care: the smallest wins.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Calls body(i) for every i in [0, count) on the TBB workers, one index per task (tiles are
// coarse enough), and returns when all are done. An exception in a body is rethrown here.
void parallelFor(std::size_t count, const std::function<void(std::size_t)>& body);

}  // namespace renderers
