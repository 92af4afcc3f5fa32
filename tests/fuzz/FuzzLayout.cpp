// libFuzzer target: layout TOML text. Any bytes give problems or a layout, never a crash, a
// hang or a huge allocation; an accepted layout honours the caps.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "wall/layout/Layout.h"
#include "wall/route/Routing.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const wall::LayoutResult r = wall::readLayoutText(
      std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.toml");
  if (!r.ok()) return 0;
  const wall::Layout& l = r.layout;
  if (l.displays.empty() || l.displays.size() > static_cast<size_t>(wall::kMaxDisplays) ||
      l.canvasWidth <= 0 || l.canvasHeight <= 0 ||
      static_cast<long long>(l.canvasWidth) * l.canvasHeight > wall::kMaxCanvasPixels)
    std::abort();  // a layout past the caps was accepted
  for (const wall::Display& d : l.displays)
    if (d.rect.x0 < 0 || d.rect.y0 < 0 || d.rect.x1 > l.canvasWidth || d.rect.y1 > l.canvasHeight)
      std::abort();  // a display outside its canvas
  // Routing must cope with whatever was accepted (a big tile keeps the work small).
  (void)wall::tilesShownByAnyDisplay(l, 1024);
  return 0;
}
