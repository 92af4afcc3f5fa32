// libFuzzer target: what a job's rank 0 or the wall's process 0 reads first on the wall
// service's directory socket (wall/service/protocol/Protocol.h): the header, a hello, a control
// message, a text message. Any bytes are accepted or refused with a base::Error (anything else
// escapes and is a crash); whatever is accepted honours the caps and packs back to the same body.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "base/Error.h"
#include "wall/service/protocol/Protocol.h"

namespace {

using namespace wall::service;

constexpr std::size_t kHeaderBytes = sizeof(MessageHeader);

// The message past its header equals `again` past its header.
bool sameBody(const std::byte* data, std::size_t size, const messaging::Bytes& again) {
  return again.size() == size &&
         std::memcmp(again.data() + kHeaderBytes, data + kHeaderBytes, size - kHeaderBytes) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* raw, std::size_t size) {
  const auto* data = reinterpret_cast<const std::byte*>(raw);
  try {
    const MessageHeader h = parseHeader(data, size);
    if (h.magic != kMagic || h.version != kProtocolVersion ||
        h.kind < static_cast<std::uint16_t>(Kind::Hello) ||
        h.kind > static_cast<std::uint16_t>(kLastKind))
      std::abort();  // a header past its checks
  } catch (const base::Error&) {
  }
  try {
    const Hello hello = parseHello(data, size);
    if (hello.token.size() > kMaxStringBytes || hello.host.size() > kMaxStringBytes ||
        hello.captureDir.size() > kMaxStringBytes || hello.renderRanks < 1 ||
        hello.framesInFlight < 1 || hello.framesInFlight > 16 || hello.codec.jpegQuality < 1 ||
        hello.codec.jpegQuality > 100)
      std::abort();  // a hello past the caps
    if (!sameBody(data, size, packHello(hello))) std::abort();
  } catch (const base::Error&) {
  }
  try {
    const Control control = parseControl(data, size);
    if (!sameBody(data, size, packControl(Kind::Presented, 0, control.value, control.second)))
      std::abort();
  } catch (const base::Error&) {
  }
  try {
    const std::string text = parseText(data, size);
    if (text.size() > kMaxStringBytes) std::abort();
    if (!sameBody(data, size, packText(Kind::Refused, 0, text))) std::abort();
  } catch (const base::Error&) {
  }
  return 0;
}
