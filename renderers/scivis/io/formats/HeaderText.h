#pragma once
// Small helpers the NRRD and MetaImage text-header parsers share: trimming, numbers that must
// parse completely, lower-casing. `where` in messages is "file:line: field 'name'".
#include <string>
#include <string_view>
#include <vector>

#include "renderers/Volume.h"

namespace renderers::headertext {

std::string_view trim(std::string_view s);
std::string lower(std::string_view s);
// Whitespace-separated numbers, each parsed completely (no trailing junk, finite).
std::vector<double> numbers(std::string_view value, const std::string& where);
// Exactly `count` numbers.
std::vector<double> numbers(std::string_view value, std::size_t count, const std::string& where);
// Exactly `count` integers in [lo, hi].
std::vector<long long> integers(std::string_view value, std::size_t count, long long lo,
                                long long hi, const std::string& where);
// Three voxel counts (x, y, z), each within the per-axis cap, then checked by checkFileDims.
Index3 fileDims(std::string_view value, const std::string& where);
// The folder of `path` joined with `name` (unless absolute).
std::string besideFile(const std::string& path, std::string_view name);

}  // namespace renderers::headertext
