#pragma once
// The one string escape the service's `--stats` JSON lines need (host names, reasons, codec
// names): quotes and backslashes escaped, control characters dropped.
#include <string>

namespace wall::service {

// `s` as a JSON string literal, quotes included.
std::string jsonText(const std::string& s);

}  // namespace wall::service
