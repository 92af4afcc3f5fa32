// The scivis renderer and the scivis parts of scene files, registered before any test runs, as
// dfbwall's main does (renderers/scivis/Registration.h): these tests read and render scivis
// scenes by name.
#include "renderers/scivis/Registration.h"

namespace {

[[maybe_unused]] const bool kSciVisRegistered = (renderers::scivis::registerSciVis(), true);

}  // namespace
