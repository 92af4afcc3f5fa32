#pragma once
// How the ranks of a job agree to stop early (docs/design.md, "Stopping"). Render rank 0
// decides: it stops when it took a stop signal itself or when another rank that took one asked
// it to. The other render ranks learn the decision from the per-frame broadcast, the wall ranks
// from the last frame rank 0 names (runtime/WallControl.h). Frames after it are never begun, so no
// piece is in flight for a frame nobody will present.
//
// One object per rank, registered under kRunControlObject on the job's messenger before the
// start-up barrier. incoming() runs on the messenger's inbox thread; the rest on the main one.
#include <cstdint>
#include <mutex>
#include <optional>

#include "apps/StopSignals.h"
#include "base/ObjectIds.h"
#include "messaging/Messenger.h"

namespace app {

constexpr messaging::ObjectId kRunControlObject = base::objectId(base::MessageObject::kRunControl);

class RunControl : public messaging::MessageHandler {
 public:
  RunControl(messaging::Messenger& messenger, StopSignals& signals);
  ~RunControl() override;
  RunControl(const RunControl&) = delete;
  RunControl& operator=(const RunControl&) = delete;

  // Between frames, any rank: takes a pending stop signal; rank 0 keeps it, another rank asks
  // rank 0 to stop (once).
  void pollSignals();
  // Any rank: asks for a graceful stop ending with `exitCode` (e.g. a window was closed).
  void askToStop(int exitCode);
  // Rank 0: the exit code of the stop asked for, if any.
  std::optional<int> stopRequested() const;

  void incoming(int fromRank, messaging::Bytes&& payload) override;

 private:
  messaging::Messenger& messenger_;
  StopSignals& signals_;
  bool asked_ = false;
  mutable std::mutex mutex_;
  std::optional<int> requested_;  // rank 0
};

}  // namespace app
