#pragma once
// The one way to run a collective in dfbwall (docs/design.md, invariant 6): the non-blocking MPI
// call completed by base::waitWithDeadline, so a rank that never joins turns into a
// base::DeadlineError on the others instead of a hang. Values travel as their bytes (T trivially
// copyable, the same layout on every rank of a job); the v-variants exchange the counts first
// (an allgather or gather of one int), work out the offsets themselves and move up to 2^31-1
// values of any size.
//
// A collective cannot be cancelled: after a DeadlineError it stays posted and MPI may still write
// the buffers it was given, so the job is expected to end; the buffers the helpers own are kept
// for the rest of the process (the caller's own, as for Pending, are the caller's to keep).
#include <mpi.h>

#include <chrono>
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "base/Error.h"

namespace base {

// How long a collective may take, and what it says when it cannot finish.
struct Bound {
  // A deadline that every wait of the call shares, or a timeout each wait counts from its start.
  std::variant<std::chrono::steady_clock::time_point, std::chrono::milliseconds> until{};
  // The DeadlineError's text when another rank has not joined in time.
  std::string late{};
  // The longest sleep between polls (base::waitWithDeadline): long for a rank that idles until
  // the next order, short where a collective usually completes at once.
  std::chrono::microseconds maxSleep{20};
  // v-variants: the Error's text when one rank's values, or all ranks' together, are more than
  // an MPI count reaches (2^31-1); empty: a text that says so.
  std::string tooLarge{};
  // Polled between tests: a reason to stop waiting before the deadline (another rank left for
  // good: it will never join), thrown as a DeadlineError with that text; empty: keep waiting.
  std::function<std::string()> unless{};

  // The deadline of a wait that starts now.
  std::chrono::steady_clock::time_point deadline() const;
  // The bound of a setup step: "WHAT: another rank did not join within N ms".
  static Bound joinWithin(std::chrono::milliseconds timeout, const std::string& what);
};

// A collective started and not yet finished: the caller works while its data travel. Its
// buffers must live until finish() returns.
class [[nodiscard]] Pending {
 public:
  explicit Pending(MPI_Request request) : request_(request) {}
  Pending(Pending&& other) noexcept : request_(other.request_) {
    other.request_ = MPI_REQUEST_NULL;
  }
  Pending(const Pending&) = delete;
  Pending& operator=(const Pending&) = delete;
  Pending& operator=(Pending&&) = delete;

  // Waits for the collective within `bound`.
  void finish(const Bound& bound);

 private:
  MPI_Request request_;
};

void barrier(MPI_Comm comm, const Bound& bound);
// `bytes` bytes at `data` from `root` to every rank.
void bcast(void* data, int bytes, int root, MPI_Comm comm, const Bound& bound);
void allreduce(const void* in, void* out, int count, MPI_Datatype type, MPI_Op op, MPI_Comm comm,
               const Bound& bound);
Pending startAllreduce(const void* in, void* out, int count, MPI_Datatype type, MPI_Op op,
                       MPI_Comm comm);

// Every rank's `mine`, in rank order: at `root` only (empty elsewhere), or on every rank.
template <class T>
std::vector<T> gather(const T& mine, int root, MPI_Comm comm, const Bound& bound);
template <class T>
std::vector<T> allgather(const T& mine, MPI_Comm comm, const Bound& bound);

// Every rank's values one after another in rank order, on every rank; `countsPerRank` (when
// given) how many came from each rank. A rank may give none.
template <class T>
std::vector<T> allgatherv(const std::vector<T>& mine, MPI_Comm comm, const Bound& bound,
                          std::vector<int>* countsPerRank = nullptr);
// Every rank's values at `root`, one vector per rank (empty elsewhere).
template <class T>
std::vector<std::vector<T>> gatherv(const std::vector<T>& mine, int root, MPI_Comm comm,
                                    const Bound& bound);

// What startGatherv gathers at the root, kept by the caller from one call to the next so a
// gather every frame reuses its memory. Counts and offsets in values; all empty off the root.
template <class T>
struct Gathered {
  std::vector<int> counts, offsets;
  std::vector<T> all;

  std::span<const T> of(int rank) const {
    const auto r = static_cast<std::size_t>(rank);
    return std::span<const T>(all).subspan(static_cast<std::size_t>(offsets[r]),
                                           static_cast<std::size_t>(counts[r]));
  }
};
// gatherv into `into`, finished by the caller: the counts are exchanged within `bound`, then
// the values travel while the caller works.
template <class T>
Pending startGatherv(std::span<const T> mine, int root, MPI_Comm comm, const Bound& bound,
                     Gathered<T>& into);

// The untyped core of the templates above.
namespace collectives {

void gatherBytes(const void* mine, void* all, int bytes, int root, MPI_Comm comm,
                 const Bound& bound);
void allgatherBytes(const void* mine, void* all, int bytes, MPI_Comm comm, const Bound& bound);
// `values` as an MPI count, or the Error of bound.tooLarge.
int countOf(std::size_t values, const Bound& bound);
// The offsets of `counts` laid one after another; returns the total, or throws the Error of
// bound.tooLarge when it is more than an MPI count reaches.
std::size_t layOut(const std::vector<int>& counts, std::vector<int>& offsets, const Bound& bound);
// MPI_Igatherv / MPI_Iallgatherv of values of `valueBytes` bytes each.
Pending startGatherv(const void* mine, int count, void* all, const std::vector<int>& counts,
                     const std::vector<int>& offsets, std::size_t valueBytes, int root,
                     MPI_Comm comm);
Pending startAllgatherv(const void* mine, int count, void* all, const std::vector<int>& counts,
                        const std::vector<int>& offsets, std::size_t valueBytes, MPI_Comm comm);

// After a DeadlineError the collective stays posted and MPI may still write the buffers it was
// given: those a helper owns are kept for the rest of the process instead of freed under it.
template <class... Buffers>
void keepWhilePosted(Buffers&&... buffers) {
  (static_cast<void>(new std::decay_t<Buffers>(std::move(buffers))), ...);
}

}  // namespace collectives

template <class T>
std::vector<T> gather(const T& mine, int root, MPI_Comm comm, const Bound& bound) {
  static_assert(std::is_trivially_copyable_v<T>);
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::vector<T> all(rank == root ? static_cast<std::size_t>(size) : 0);
  try {
    collectives::gatherBytes(&mine, all.data(), static_cast<int>(sizeof(T)), root, comm, bound);
  } catch (const DeadlineError&) {
    collectives::keepWhilePosted(std::move(all));
    throw;
  }
  return all;
}

template <class T>
std::vector<T> allgather(const T& mine, MPI_Comm comm, const Bound& bound) {
  static_assert(std::is_trivially_copyable_v<T>);
  int size = 1;
  MPI_Comm_size(comm, &size);
  std::vector<T> all(static_cast<std::size_t>(size));
  try {
    collectives::allgatherBytes(&mine, all.data(), static_cast<int>(sizeof(T)), comm, bound);
  } catch (const DeadlineError&) {
    collectives::keepWhilePosted(std::move(all));
    throw;
  }
  return all;
}

template <class T>
std::vector<T> allgatherv(const std::vector<T>& mine, MPI_Comm comm, const Bound& bound,
                          std::vector<int>* countsPerRank) {
  static_assert(std::is_trivially_copyable_v<T>);
  const int count = collectives::countOf(mine.size(), bound);
  std::vector<int> counts = allgather(count, comm, bound), offsets;
  std::vector<T> all(collectives::layOut(counts, offsets, bound));
  try {
    collectives::startAllgatherv(mine.data(), count, all.data(), counts, offsets, sizeof(T), comm)
        .finish(bound);
  } catch (const DeadlineError&) {
    collectives::keepWhilePosted(std::move(all), std::move(counts), std::move(offsets));
    throw;
  }
  if (countsPerRank) *countsPerRank = std::move(counts);
  return all;
}

template <class T>
Pending startGatherv(std::span<const T> mine, int root, MPI_Comm comm, const Bound& bound,
                     Gathered<T>& into) {
  static_assert(std::is_trivially_copyable_v<T>);
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int count = collectives::countOf(mine.size(), bound);
  into.counts.resize(rank == root ? static_cast<std::size_t>(size) : 0);
  collectives::gatherBytes(&count, into.counts.data(), static_cast<int>(sizeof count), root, comm,
                           bound);
  into.all.resize(collectives::layOut(into.counts, into.offsets, bound));
  return collectives::startGatherv(mine.data(), count, into.all.data(), into.counts, into.offsets,
                                   sizeof(T), root, comm);
}

template <class T>
std::vector<std::vector<T>> gatherv(const std::vector<T>& mine, int root, MPI_Comm comm,
                                    const Bound& bound) {
  Gathered<T> gathered;
  try {
    startGatherv(std::span<const T>(mine), root, comm, bound, gathered).finish(bound);
  } catch (const DeadlineError&) {
    collectives::keepWhilePosted(std::move(gathered));
    throw;
  }
  std::vector<std::vector<T>> out;
  for (std::size_t r = 0; r < gathered.counts.size(); ++r) {
    const std::span<const T> part = gathered.of(static_cast<int>(r));
    out.emplace_back(part.begin(), part.end());
  }
  return out;
}

}  // namespace base
