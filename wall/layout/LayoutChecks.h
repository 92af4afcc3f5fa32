#pragma once
// Inside wall/: the semantic checks behind validateLayout, restricted to displays the reader
// could trust (a display with a type error is skipped instead of producing follow-on noise).
#include <vector>

#include "base/TomlDiagnostics.h"
#include "wall/layout/Layout.h"

namespace wall::detail {

// `trusted` has one entry per display, or is empty for "all". Problems go to `report`.
// `processGaps`: process indices need not run from 0 without gaps (a window's layout).
void validateDisplays(const Layout& layout, const std::vector<bool>& trusted,
                      base::TomlDiagnostics& report, bool processGaps = false);

}  // namespace wall::detail
