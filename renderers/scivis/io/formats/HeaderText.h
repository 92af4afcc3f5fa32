#pragma once
// Small helpers the NRRD and MetaImage text-header parsers share: where a value is, trimming,
// numbers that must parse completely, lower-casing. Problems are base::Errors located at the
// value: "FILE:LINE:COLUMN: field 'sizes': ...".
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "base/Error.h"
#include "renderers/Volume.h"

namespace renderers::scivis::headertext {

// A field's value in a header: the place of its first character (columns count bytes; headers
// are ASCII) and the field's name.
struct HeaderField {
  base::SourceLocation where;
  std::string name;

  // `offset`: bytes into the value, where the problem is.
  [[noreturn]] void fail(const std::string& what, std::size_t offset = 0) const;
  // The same field, its value starting `offset` bytes further on.
  HeaderField at(std::size_t offset) const;
};

// The field named `name` whose value `value` lies in `line` (line `lineNumber` of `path`).
HeaderField fieldAt(const std::string& path, int lineNumber, std::string_view line,
                    std::string_view value, std::string name);

std::string_view trim(std::string_view s);
std::string lower(std::string_view s);
// Whitespace-separated numbers, each parsed completely (no trailing junk, finite).
std::vector<double> numbers(std::string_view value, const HeaderField& f);
// Exactly `count` numbers.
std::vector<double> numbers(std::string_view value, std::size_t count, const HeaderField& f);
// Exactly `count` integers in [lo, hi].
std::vector<long long> integers(std::string_view value, std::size_t count, long long lo,
                                long long hi, const HeaderField& f);
// Three voxel counts (x, y, z), each within the per-axis cap and in all (fileDimsProblem).
Index3 fileDims(std::string_view value, const HeaderField& f);
// The folder of `path` joined with `name` (unless absolute).
std::string besideFile(const std::string& path, std::string_view name);

}  // namespace renderers::scivis::headertext
