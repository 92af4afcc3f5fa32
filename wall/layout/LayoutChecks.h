#pragma once
// Inside wall/: the semantic checks behind validateLayout, restricted to displays the reader
// could trust (a display with a type error is skipped instead of producing follow-on noise).
#include <vector>

#include "wall/layout/Layout.h"

namespace wall::detail {

// `trusted` has one entry per display, or is empty for "all".
Problems validateDisplays(const Layout& layout, const std::vector<bool>& trusted);

}  // namespace wall::detail
