#pragma once
// Text a peer sent (a host name, a reason, a path), made safe for the wall's log: every byte
// that is not printable ASCII is escaped (\n, \xNN) and what is longer than `maxBytes` is cut,
// saying how long it was. A stranger can neither forge log lines nor fill the log.
#include <cstddef>
#include <string>
#include <string_view>

namespace wall::service {

constexpr std::size_t kMaxPeerTextBytes = 80;

std::string peerText(std::string_view text, std::size_t maxBytes = kMaxPeerTextBytes);

}  // namespace wall::service
