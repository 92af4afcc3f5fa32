#include "runtime/RenderWall.h"

#include "renderers/FrameDriver.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace runtime {

std::vector<bool> routeToDisplays(dfb::DfbOptions& options, const wall::Layout& layout,
                                  int tileSize) {
  std::vector<bool> active = wall::tilesShownByAnyDisplay(layout, tileSize);
  options.ownership = renderers::activeTileOwnership(active);
  options.format = dfb::DisplayFormat::NONE;
  return active;
}

RenderWall::RenderWall(messaging::Messenger& messenger, int renderRank,
                       const RenderWallSettings& settings,
                       std::function<void(const std::string&)> onServiceError)
    : messenger_(messenger), settings_(settings), renderRank_(renderRank) {
  const wall::Layout& layout = *settings.layout;
  if (!settings.gather) {
    if (settings.directory) {
      routeWith(*settings.directory);
    } else {
      routing_ = std::make_shared<wall::DisplayRoutingOp>(messenger, layout, settings.roles,
                                                          settings.tileSize);
    }
  }
  if (renderRank != 0) return;
  if (settings.service) {
    credits_ = std::make_unique<wall::FrameCredits>();
    settings.service->start(*credits_, std::move(onServiceError));
    serviceControl_ = std::make_unique<ServiceWallControl>(*settings.service);
    control_ = serviceControl_.get();
  } else {
    credits_ = std::make_unique<wall::FrameCredits>(messenger);
    control_ = settings.mpiControl;
  }
}

RenderWall::~RenderWall() {
  // The service link's thread writes into the credits: it goes first when this holds it last.
  serviceControl_.reset();
  settings_.service.reset();
}

void RenderWall::routeWith(const wall::service::Directory& directory) {
  // The previous sink goes first: its sockets send what they still hold before they close.
  routing_.reset();
  serviceSink_.reset();
  serviceSink_ = std::make_shared<wall::service::ServicePieceSink>(
      directory, settings_.credentials, renderRank_, settings_.codec,
      static_cast<int>(settings_.timeout.count()));
  routing_ =
      std::make_shared<wall::DisplayRoutingOp>(serviceSink_, directory.layout, settings_.tileSize);
}

std::uint32_t RenderWall::reshapeVersionFor(std::uint32_t frameId, std::uint32_t applied) const {
  if (!settings_.service) return applied;
  const wall::service::ServiceClient::ReshapeNews news = settings_.service->reshapeNews();
  return news.version != applied && frameId >= news.fromFrame ? news.version : applied;
}

bool RenderWall::reshapeAhead(std::uint32_t applied) const {
  return settings_.service && settings_.service->reshapeNews().version != applied;
}

std::optional<wall::service::Reshape> RenderWall::followReshape(std::uint32_t ordered,
                                                                MPI_Comm renderComm) {
  if (!serviceSink_ || ordered == reshapeVersion_) return std::nullopt;
  wall::service::Reshape reshape =
      wall::service::shareReshape(renderComm, settings_.service.get(), settings_.timeout);
  moved_ = std::make_unique<wall::service::Directory>(reshape.directory);
  settings_.layout = &moved_->layout;
  settings_.directory = moved_.get();
  routeWith(*moved_);
  rosterVersion_ = moved_->rosterVersion;
  reshapeVersion_ = ordered;
  return reshape;
}

void RenderWall::attach(dfb::DistributedFrameBuffer& fb) {
  if (routing_) fb.addPixelOp(routing_);
}

void RenderWall::waitForCredit(std::uint32_t frameId) const {
  if (credits_)
    credits_->waitForPresented(static_cast<std::int64_t>(frameId) - settings_.framesInFlight,
                               settings_.timeout);
}

std::uint32_t RenderWall::rosterVersion() const {
  return settings_.service ? settings_.service->rosterVersion() : 0;
}

std::optional<wall::service::Roster> RenderWall::followRoster(std::uint32_t ordered,
                                                              MPI_Comm renderComm) {
  if (!serviceSink_ || ordered == rosterVersion_) return std::nullopt;
  wall::service::Roster roster =
      wall::service::shareRoster(renderComm, settings_.service.get(), settings_.timeout);
  serviceSink_->setRoster(roster);
  rosterVersion_ = ordered;
  return roster;
}

void RenderWall::endFrame(std::uint32_t frameId) {
  if (routing_) routing_->endFrame(frameId);
}

wall::DisplayRoutingOp::Sent RenderWall::relayGathered(std::uint32_t frameId,
                                                       const std::vector<std::uint32_t>& image) {
  wall::DisplayRoutingOp::Sent sent;
  const wall::Layout& layout = *settings_.layout;
  for (size_t d = 0; d < layout.displays.size(); ++d) {
    const dfb::Region& rect = layout.displays[d].rect;
    const int to = settings_.roles.rankOfProcess(layout.displays[d].process);
    messaging::Bytes piece = wall::packPiece(
        frameId, static_cast<int>(d), dfb::Region{0, 0, rect.width(), rect.height()}, image.data(),
        layout.canvasWidth, rect.x0, rect.y0, messenger_.compresses(to));
    sent.bytes += piece.size();
    sent.pieces++;
    if (!messenger_.sameHost(to)) sent.piecesToOtherHosts++;
    messenger_.send(to, wall::kWallNodeObject, std::move(piece));
  }
  return sent;
}

void RenderWall::finish(std::uint32_t lastFrame, int exitCode, bool wallKnowsLastFrame) {
  if (!control_) return;
  if (!wallKnowsLastFrame || settings_.service) control_->lastFrame(lastFrame, exitCode);
  if (credits_) credits_->waitForPresented(lastFrame, settings_.timeout);
}

}  // namespace runtime
