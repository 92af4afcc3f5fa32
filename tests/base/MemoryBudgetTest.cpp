// The memory budget's arithmetic, sizes as --memory-limit takes them, and the limit itself.
#include "base/MemoryBudget.h"

#include <gtest/gtest.h>

#include <limits>

namespace dfb {
namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

TEST(MemoryBudget, SizesSaturateInsteadOfWrapping) {
  EXPECT_EQ(base::bytesTimes(1ull << 40, 1ull << 30), kMax);
  EXPECT_EQ(base::bytesTimes(16384ull * 16384 * 16384, 4), 17592186044416ull);
  EXPECT_EQ(base::bytesPlus(kMax - 1, 2), kMax);
  EXPECT_EQ(base::bytesPlus(1, 2), 3u);
}

TEST(MemoryBudget, ParsesByteSizes) {
  EXPECT_EQ(base::parseByteSize("123"), 123u);
  EXPECT_EQ(base::parseByteSize("64M"), 64ull << 20);
  EXPECT_EQ(base::parseByteSize("2G"), 2ull << 30);
  EXPECT_EQ(base::parseByteSize("2gib"), 2ull << 30);
  EXPECT_EQ(base::parseByteSize("1.5G"), 3ull << 29);
  EXPECT_EQ(base::parseByteSize("512k"), 512ull << 10);
  EXPECT_EQ(base::parseByteSize("1T"), 1ull << 40);
  for (const char* bad : {"", "G", "0", "-1", "1.5", "1X", "12MBs", "1..5G", "99999999T", "nan"})
    EXPECT_FALSE(base::parseByteSize(bad).has_value()) << bad;
}

TEST(MemoryBudget, TextsAndTheLimit) {
  EXPECT_EQ(base::byteText(12), "12 bytes");
  EXPECT_EQ(base::byteText(1536), "1.5 KiB");
  EXPECT_EQ(base::byteText(64ull << 20), "64 MiB");
  EXPECT_EQ(base::byteText(17592186044416ull), "16 TiB");
  // Without a limit set, the machine's memory: some, but not everything.
  base::setMemoryLimit(0);
  const std::uint64_t machine = base::memoryLimit();
  EXPECT_GT(machine, 64ull << 20);
  EXPECT_LT(machine, kMax);
  base::setRanksOnHost(4);
  EXPECT_EQ(base::memoryLimit(), machine / 4);
  EXPECT_NE(base::memoryLimitText().find(", shared by 4 ranks"), std::string::npos)
      << base::memoryLimitText();
  base::setRanksOnHost(1);
  base::setMemoryLimit(1 << 20);
  EXPECT_EQ(base::memoryProblem(1 << 20), "");
  EXPECT_EQ(base::memoryProblem((1 << 20) + 1),
            "needs 1 MiB (1048577 bytes), more than this rank may hold: 1 MiB (1048576 bytes: "
            "--memory-limit)");
  EXPECT_EQ(base::memoryProblem(kMax).rfind("needs 16 EiB (more than 2^64 bytes)", 0), 0u);
  base::setMemoryLimit(0);
}

}  // namespace
}  // namespace dfb
