#pragma once
// All TBB use of the renderers, behind these names, and the floating-point mode their threads
// render in.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace base {

// Caps the worker threads of the whole process while it lives (tbb::global_control);
// threads <= 0 leaves TBB's default. Nest or overlap them only with care: the smallest wins.
// For the dfbwall executable, which owns its process; a library embedded in a program uses a
// TaskArena instead, which caps only its own work.
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

// A TBB task arena of its own (tbb::task_arena): work run through execute(), and every
// parallelFor inside it, uses at most `threads` threads (the caller's included; <= 0: TBB's
// default, the cores) and leaves the rest of the process's TBB parallelism alone. Its tasks run
// with flush-to-zero and denormals-are-zero on — the mode every renderer sets for its tiles
// (enableFlushToZero) — on whichever thread, whatever mode the caller is in: work planned in it
// (which every rank must do bit for bit alike) never depends on the calling thread's mode.
// execute() changes the caller's mode while it runs: pair it with a FloatModeGuard.
class TaskArena {
 public:
  explicit TaskArena(int threads);
  ~TaskArena();
  TaskArena(const TaskArena&) = delete;
  TaskArena& operator=(const TaskArena&) = delete;

  // Runs `work` on the calling thread inside the arena; an exception in it is rethrown here.
  void execute(const std::function<void()>& work);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Saves the calling thread's flush-to-zero and denormals-are-zero bits (MXCSR) and restores them
// when it goes out of scope, also while an exception unwinds: rendering sets both on whatever
// thread runs a tile, and a thread of a program that embeds us must get its own mode back.
class FloatModeGuard {
 public:
  FloatModeGuard();
  ~FloatModeGuard();
  FloatModeGuard(const FloatModeGuard&) = delete;
  FloatModeGuard& operator=(const FloatModeGuard&) = delete;

 private:
  unsigned flushZero_, denormalsZero_;
};

// Calls body(i) for every i in [0, count) on the TBB workers (of the current arena), one index
// per task (tiles are coarse enough), and returns when all are done. An exception in a body is
// rethrown here.
void parallelFor(std::size_t count, const std::function<void(std::size_t)>& body);

// Sorts `values` ascending on the TBB workers (of the current arena). Not stable: equal values
// may come out in any order, which for integers changes nothing.
void parallelSort(std::vector<std::uint64_t>& values);

}  // namespace base
