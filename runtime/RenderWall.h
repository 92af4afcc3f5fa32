#pragma once
// The render side of a job's wall, for every render rank: which tiles are rendered and how the
// DFB finishes them, where the pieces go (the job's own wall ranks through the messenger, or a
// wall service's processes through its sockets), and on render rank 0 the frame credits and the
// job's words to the wall (runtime/WallControl.h). Made before the start-up barrier.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dfb/DistributedFrameBuffer.h"
#include "messaging/Messenger.h"
#include "runtime/WallControl.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"
#include "wall/route/DisplayRoutingOp.h"
#include "wall/route/FrameCredits.h"
#include "wall/service/client/ServiceClient.h"
#include "wall/service/protocol/Codec.h"
#include "wall/service/protocol/Protocol.h"

namespace runtime {

struct RenderWallSettings {
  const wall::Layout* layout = nullptr;  // never null: a job without a wall has no RenderWall
  wall::RankRoles roles;
  bool gather = false;  // whole displays from rank 0's gathered image instead of routed pieces
  int tileSize = 64;
  int framesInFlight = 2;
  std::chrono::milliseconds timeout{60000};
  // A wall service: its directory (every rank) and render rank 0's link to it.
  const wall::service::Directory* directory = nullptr;
  wall::service::Credentials credentials;  // what the piece sockets present (every rank)
  std::shared_ptr<wall::service::ServiceClient> service;
  wall::service::CodecSpec codec;
  // The job's own wall ranks: every rank's wall control (render rank 0 speaks through it).
  MpiWallControl* mpiControl = nullptr;
};

// Sets `options` to route: only tiles some display shows are rendered, each owned where it is
// rendered, and nothing gathered. Returns the tiles rendered.
std::vector<bool> routeToDisplays(dfb::DfbOptions& options, const wall::Layout& layout,
                                  int tileSize);

class RenderWall {
 public:
  // `onServiceError`: render rank 0, what a wall service ending the job or going silent says.
  RenderWall(messaging::Messenger& messenger, int renderRank, const RenderWallSettings& settings,
             std::function<void(const std::string&)> onServiceError);
  ~RenderWall();
  RenderWall(const RenderWall&) = delete;
  RenderWall& operator=(const RenderWall&) = delete;

  // Routes `fb`'s finished tiles to the displays (not in gather mode).
  void attach(dfb::DistributedFrameBuffer& fb);

  // Render rank 0, before it orders frame `frameId`: waits until the wall presented frame
  // frameId - framesInFlight.
  void waitForCredit(std::uint32_t frameId) const;
  // Render rank 0: the wall service's roster version the next frame routes with (0: none).
  std::uint32_t rosterVersion() const;
  // Every render rank, with the version its frame order carries: the wall's new roster when it
  // changed (a collective over `renderComm`), which the pieces of this frame on follow.
  std::optional<wall::service::Roster> followRoster(std::uint32_t ordered, MPI_Comm renderComm);
  // Render rank 0: the version of the move of the job's window (Protocol.h, Reshape) that frame
  // `frameId` renders with: the newest the wall sent whose switch frame it has reached, else
  // `applied` (the one the ranks follow now). A move sent but not reached yet: reshapeAhead.
  std::uint32_t reshapeVersionFor(std::uint32_t frameId, std::uint32_t applied) const;
  bool reshapeAhead(std::uint32_t applied) const;
  std::uint32_t reshapeVersion() const { return reshapeVersion_; }
  // Every render rank, between frames, with the version its frame order carries: the wall's move
  // when it is new to this rank (a collective over `renderComm`). The pieces go to the new
  // window's processes under its piece session from then on; attach() the new frame buffer.
  std::optional<wall::service::Reshape> followReshape(std::uint32_t ordered, MPI_Comm renderComm);
  // The layout pieces are routed by (the directory's, or the newest move's).
  const wall::Layout& layout() const { return *settings_.layout; }
  // This rank finished frame `frameId`: the pieces held back go.
  void endFrame(std::uint32_t frameId);
  // Gather mode, render rank 0: each display its rectangle of the whole image, as Tide-like
  // walls do it. Returns what was sent.
  wall::DisplayRoutingOp::Sent relayGathered(std::uint32_t frameId,
                                             const std::vector<std::uint32_t>& image);
  // Render rank 0, after the last frame: tells the wall unless its processes know it already
  // (a frame count they were given; a wall service is always told), then waits for its credit.
  void finish(std::uint32_t lastFrame, int exitCode, bool wallKnowsLastFrame);

  WallControl* control() const { return control_; }               // render rank 0
  wall::FrameCredits* credits() const { return credits_.get(); }  // render rank 0
  wall::DisplayRoutingOp* routing() const { return routing_.get(); }
  wall::service::ServicePieceSink* serviceSink() const { return serviceSink_.get(); }

 private:
  messaging::Messenger& messenger_;
  RenderWallSettings settings_;
  std::shared_ptr<wall::service::ServicePieceSink> serviceSink_;
  std::shared_ptr<wall::DisplayRoutingOp> routing_;
  std::unique_ptr<wall::FrameCredits> credits_;
  std::unique_ptr<ServiceWallControl> serviceControl_;
  WallControl* control_ = nullptr;
  std::uint32_t rosterVersion_ = 0;   // of the roster the pieces follow (0: the directory's)
  std::uint32_t reshapeVersion_ = 0;  // of the move the pieces follow (0: the directory's window)
  std::unique_ptr<wall::service::Directory> moved_;  // the newest move's directory
  int renderRank_ = 0;
  void routeWith(const wall::service::Directory& directory);
};

}  // namespace runtime
