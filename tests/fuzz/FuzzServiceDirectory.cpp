// libFuzzer target: the directory a wall sends a job it accepted, or with a moved window in a
// Reshape (wall/service/protocol/Protocol.h), as a render job's rank 0 reads it. Any bytes are
// refused with a base::Error (anything else escapes and is a crash) or give a directory whose
// layout passes the layout checks: displays inside the canvas, processes 0..W-1 with an endpoint
// each; it packs and parses back the same.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "base/Error.h"
#include "wall/layout/Layout.h"
#include "wall/service/protocol/Protocol.h"

namespace {

using namespace wall::service;

// A directory that passed the parser honours the caps and survives packing.
void checkDirectory(const Directory& d) {
  const wall::Layout& l = d.layout;
  if (l.displays.empty() || l.displays.size() > static_cast<std::size_t>(wall::kMaxDisplays) ||
      l.canvasWidth <= 0 || l.canvasHeight <= 0 ||
      static_cast<long long>(l.canvasWidth) * l.canvasHeight > wall::kMaxCanvasPixels ||
      l.processCount != static_cast<int>(d.processes.size()) || d.framesInFlight < 1 ||
      d.framesInFlight > 16)
    std::abort();  // a directory past the caps
  for (const wall::Display& display : l.displays)
    if (display.rect.empty() || display.rect.x0 < 0 || display.rect.y0 < 0 ||
        display.rect.x1 > l.canvasWidth || display.rect.y1 > l.canvasHeight ||
        display.process < 0 || display.process >= l.processCount)
      std::abort();  // a display outside its canvas or driven by no process
  if (!wall::validateLayout(l, true).empty()) std::abort();
  const messaging::Bytes packed = packDirectory(d);
  const Directory back = parseDirectory(packed.data(), packed.size());
  bool same = back.session == d.session && back.framesInFlight == d.framesInFlight &&
              back.timeoutMs == d.timeoutMs && back.layout.file == l.file &&
              back.window == d.window && back.layout.canvasWidth == l.canvasWidth &&
              back.layout.canvasHeight == l.canvasHeight &&
              back.layout.processCount == l.processCount &&
              back.layout.displays.size() == l.displays.size() &&
              back.processes.size() == d.processes.size();
  for (std::size_t i = 0; same && i < l.displays.size(); ++i)
    same = back.layout.displays[i].name == l.displays[i].name &&
           back.layout.displays[i].rect == l.displays[i].rect &&
           back.layout.displays[i].process == l.displays[i].process;
  for (std::size_t i = 0; same && i < d.processes.size(); ++i)
    same = back.processes[i].endpoint == d.processes[i].endpoint;
  if (!same) std::abort();  // a directory that does not survive packing
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* raw, std::size_t size) {
  const auto* data = reinterpret_cast<const std::byte*>(raw);
  try {
    checkDirectory(parseDirectory(data, size));
  } catch (const base::Error&) {
  }
  try {
    const Reshape r = parseReshape(data, size);
    if (r.version == 0 || r.fromFrame == 0 || r.directory.session == 0 ||
        r.directory.session == r.session)
      std::abort();  // a reshape past its checks
    checkDirectory(r.directory);
    const messaging::Bytes packed = packReshape(r);
    const Reshape back = parseReshape(packed.data(), packed.size());
    if (back.version != r.version || back.fromFrame != r.fromFrame ||
        back.directory.session != r.directory.session)
      std::abort();
  } catch (const base::Error&) {
  }
  return 0;
}
