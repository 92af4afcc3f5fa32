#include "apps/RunControl.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace app {
namespace {

struct ControlMessage {
  std::uint32_t kind;  // kAskToStop (to rank 0)
  std::uint32_t unused;
  std::int32_t exitCode;
};
constexpr std::uint32_t kAskToStop = 1;

messaging::Bytes pack(const ControlMessage& m) {
  messaging::Bytes bytes(sizeof m);
  std::memcpy(bytes.data(), &m, sizeof m);
  return bytes;
}

}  // namespace

RunControl::RunControl(messaging::Messenger& messenger, StopSignals& signals)
    : messenger_(messenger), signals_(signals) {
  messenger_.registerObject(kRunControlObject, this);
}

RunControl::~RunControl() { messenger_.unregisterObject(kRunControlObject); }

void RunControl::pollSignals() {
  const int signal = signals_.poll();
  if (signal == 0) return;
  askToStop(exitCodeForStop(signal));
}

void RunControl::askToStop(int code) {
  if (messenger_.rank() == 0) {
    std::lock_guard lock(mutex_);
    if (!requested_) requested_ = code;
  } else if (!asked_) {
    asked_ = true;
    messenger_.send(0, kRunControlObject, pack({kAskToStop, 0, code}));
  }
}

std::optional<int> RunControl::stopRequested() const {
  std::lock_guard lock(mutex_);
  return requested_;
}

void RunControl::incoming(int fromRank, messaging::Bytes&& payload) {
  ControlMessage m;
  if (payload.size() != sizeof m)
    throw std::runtime_error("malformed run-control message of " + std::to_string(payload.size()) +
                             " bytes from rank " + std::to_string(fromRank));
  std::memcpy(&m, payload.data(), sizeof m);
  if (m.kind != kAskToStop || messenger_.rank() != 0)
    throw std::runtime_error("run-control message of unknown kind " + std::to_string(m.kind) +
                             " from rank " + std::to_string(fromRank));
  std::lock_guard lock(mutex_);
  if (!requested_) requested_ = m.exitCode;
}

}  // namespace app
