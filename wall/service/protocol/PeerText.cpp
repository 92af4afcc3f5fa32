#include "wall/service/protocol/PeerText.h"

#include <algorithm>

namespace wall::service {

std::string peerText(std::string_view text, std::size_t maxBytes) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  const std::size_t kept = std::min(text.size(), maxBytes);
  out.reserve(kept + 16);
  for (std::size_t i = 0; i < kept; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (kept < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace wall::service
