// libFuzzer target: piece messages past the parser, into a wall node's assembly (claim under
// the lock, copy into the frame's display buffers), as the node's handler threads take them.
// The input is records (a 16-bit length and a piece message, the first byte of the length's
// record the sending rank); every record goes to WallNode::incoming. Assembly never touches a
// presenter (only presentFrame does), so the node gets none: no GL.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

#include "base/Error.h"
#include "wall/display/WallNode.h"
#include "wall/display/WallPeers.h"
#include "wall/layout/Layout.h"

namespace {

// Two small displays on one wall process, one of them at an offset that cuts tiles.
constexpr std::string_view kLayout = R"(
[[display]]
name = "left"
origin = [0, 0]
size = [20, 12]
process = 0

[[display]]
name = "right"
origin = [22, 3]
size = [13, 9]
process = 0
)";

// A wall of one process: every agreement is with itself. Assembly calls none of these.
class OneProcess : public wall::WallPeers {
 public:
  int process() const override { return 0; }
  int processCount() const override { return 1; }
  void agreeMax(std::uint32_t, std::int64_t*, int, Clock::time_point) override {}
  std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint32_t,
                                                        std::vector<std::uint32_t> mine,
                                                        Clock::time_point) override {
    return {std::move(mine)};
  }
  void presented(std::uint32_t, std::int64_t) override {}
};

const wall::Layout& layout() {
  static const wall::Layout l = [] {
    wall::LayoutResult r = wall::readLayoutText(kLayout, "fuzz-wall.toml");
    if (!r.ok()) std::abort();
    return r.layout;
  }();
  return l;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  OneProcess peers;
  wall::WallNodeOptions options;
  options.tileSize = 8;
  options.gatherMode = data[0] & 1;
  options.framesAhead = 3;
  wall::WallNode node(layout(), peers, {nullptr, nullptr}, options);
  size_t at = 1;
  while (at + 3 <= size) {
    const int fromRank = data[at];
    std::uint16_t length;
    std::memcpy(&length, data + at + 1, sizeof length);
    at += 3;
    if (length > size - at) break;
    const auto* bytes = reinterpret_cast<const std::byte*>(data + at);
    node.incoming(fromRank, messaging::Bytes(bytes, bytes + length));
    at += length;
  }
  return 0;
}
