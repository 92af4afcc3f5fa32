#pragma once
// The files of a volume time series, as a [[volumes]] entry names them: a printf pattern with one
// integer field ("step-%03d.nrrd": the steps first_step, first_step + 1, ...) or a glob
// ("run/*.nii.gz": every match, in name order). Pure, apart from the glob's directory listing.
#include <cstdint>
#include <string>
#include <vector>

namespace renderers::scivis {

enum class SeriesNaming { One, Pattern, Glob };

// How `file` names its steps: a '%' makes a pattern ("%%" is a plain '%'), '*', '?' or '[' a
// glob, anything else one file.
SeriesNaming seriesNaming(const std::string& file);

// Step `step` of printf pattern `pattern`: its one field (%d, %Nd or %0Nd; N up to 20) replaced
// by `step`. Throws base::Error saying what is wrong with a pattern that has no such field, or
// more than one, or another conversion.
std::string patternFile(const std::string& pattern, std::uint64_t step);

// The files matching glob `pattern`, sorted by name (byte order); throws base::Error when none
// does or the listing fails.
std::vector<std::string> globFiles(const std::string& pattern);

}  // namespace renderers::scivis
