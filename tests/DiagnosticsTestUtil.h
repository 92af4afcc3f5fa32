#pragma once
// Comparing the problems of an input file (base/TomlDiagnostics.h) by their headlines: each
// problem is a line "FILE:LINE:COLUMN: FIELD: MESSAGE" followed by indented lines that echo the
// file (checked on their own in tests/base/TomlDiagnosticsTest.cpp).
#include <sstream>
#include <string>

namespace testutil {

// `text` without the echoed lines: one headline per problem, joined by '\n'.
inline std::string headlines(const std::string& text) {
  std::istringstream in(text);
  std::string out, line;
  while (std::getline(in, line))
    if (line.empty() || line.front() != ' ') out += (out.empty() ? "" : "\n") + line;
  return out;
}

}  // namespace testutil
