// libFuzzer target: what a wall's head reads from its processes' links and a job reads from the
// wall when processes come and go (wall/service/protocol/LinkMessages.h; Roster in Protocol.h). The
// first byte picks the parser. Any bytes are refused with a base::Error (anything else escapes and
// is a crash) or give a message within its caps that packs and parses back the same.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "base/Error.h"
#include "wall/layout/Layout.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/ServiceCommands.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* raw, std::size_t size) {
  using namespace wall::service;
  if (size < 1) return 0;
  const auto* data = reinterpret_cast<const std::byte*>(raw + 1);
  const std::size_t n = size - 1;
  try {
    switch (raw[0] % 5) {
      case 0: {
        const Join j = parseJoin(data, n);
        const messaging::Bytes again = packJoin(j);
        const Join back = parseJoin(again.data(), again.size());
        if (back.token != j.token || back.process != j.process || back.host != j.host ||
            back.pieceEndpoint != j.pieceEndpoint || back.layoutHash != j.layoutHash ||
            back.incarnation != j.incarnation)
          std::abort();
        break;
      }
      case 1: {
        const BarrierValues b = parseBarrier(data, n);
        if (b.values.empty() || b.values.size() > 16) std::abort();
        const messaging::Bytes again = packBarrier(1, b);
        if (parseBarrier(again.data(), again.size()).values != b.values) std::abort();
        break;
      }
      case 2: {
        const CapturePixels c = parsePixels(data, n);
        if (c.pixels.size() * sizeof(std::uint32_t) > n) std::abort();  // more than was sent
        break;
      }
      case 3: {
        const Roster r = parseRoster(data, n);
        if (r.processes.empty() ||
            r.processes.size() > static_cast<std::size_t>(wall::kMaxDisplays))
          std::abort();
        for (const DirectoryProcess& p : r.processes)
          if (p.live && p.endpoint.empty()) std::abort();
        const messaging::Bytes again = packRoster(r);
        const Roster back = parseRoster(again.data(), again.size());
        if (back.version != r.version || back.fromFrame != r.fromFrame ||
            back.processes.size() != r.processes.size() || back.why != r.why)
          std::abort();
        break;
      }
      default: {
        const ServiceCommand c = parseCommand(commandBody(data, n));
        if (c.text.size() > kMaxStringBytes) std::abort();
        break;
      }
    }
  } catch (const base::Error&) {
  }
  return 0;
}
