#pragma once
// The memory budget: how many bytes this process may hold of data whose size comes from its input
// (voxels, particles, triangles, ghost shells, images, captures). Loaders ask before they
// allocate, so a scene that asks for more than the machine has is refused with a message naming
// what asked and how many bytes, not ended by the kernel's OOM killer or a bare std::bad_alloc.
//
// The limit is the one set by setMemoryLimit (dfbwall --memory-limit), else the memory this
// process can use — the smallest of the machine's physical memory (sysconf), the cgroup's
// memory.max and RLIMIT_AS — shared evenly by the ranks of the job on this host
// (setRanksOnHost). Callers pass the total they will hold (what they hold already plus what they
// are about to allocate): the budget keeps no account of its own.
//
// Thread-safe. Sizes are std::uint64_t and computed with bytesTimes, so a size from a hostile
// input saturates instead of wrapping into a small number.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace base {

// The bytes this process may hold.
std::uint64_t memoryLimit();
// Where the limit comes from, for messages: "7.6 GiB (8160000000 bytes: physical memory shared
// by 2 ranks on this host; --memory-limit sets it)".
std::string memoryLimitText();
// `bytes` > 0: the limit, whatever the machine has; 0: back to the machine's memory.
void setMemoryLimit(std::uint64_t bytes);
// The ranks of this job on this host (>= 1), sharing its memory when no limit is set.
void setRanksOnHost(int ranks);

// Empty when `bytes` fit in the limit, else why not, as the end of a sentence naming what asks:
// "needs 16 TiB (17592186044416 bytes), more than this rank may hold: 7.6 GiB (...)".
std::string memoryProblem(std::uint64_t bytes);

// a * b and a + b, saturating at UINT64_MAX.
std::uint64_t bytesTimes(std::uint64_t a, std::uint64_t b);
std::uint64_t bytesPlus(std::uint64_t a, std::uint64_t b);

// "1.5 GiB", "512 KiB", "12 bytes".
std::string byteText(std::uint64_t bytes);
// "BYTES", or a number with a suffix K, M, G or T (powers of 1024; "KiB", "MB", "GiB" too, any
// case), e.g. "64M", "2G", "1.5G": the bytes, or nullopt for anything else, zero or over 2^63.
std::optional<std::uint64_t> parseByteSize(std::string_view text);

}  // namespace base
