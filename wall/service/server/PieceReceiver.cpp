#include "wall/service/server/PieceReceiver.h"

#include <vector>

#include "base/Error.h"
#include "wall/image/Image.h"

namespace wall::service {
namespace {
constexpr std::size_t kMaxLogged = 1024;

std::string hex(const zmq::message_t& id) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  const auto* b = static_cast<const unsigned char*>(id.data());
  for (size_t i = 0; i < id.size() && i < 8; ++i) {
    s += digits[b[i] >> 4];
    s += digits[b[i] & 15];
  }
  return s;
}
}  // namespace

PieceReceiver::PieceReceiver(const std::string& bindEndpoint, const Credentials& credentials,
                             int handlerThreads, int deadPeerMs, Log log)
    : gatekeeper_(context_, credentials, log),
      socket_(context_, zmq::socket_type::router),
      log_(std::move(log)),
      arena_(handlerThreads > 0 ? handlerThreads : tbb::task_arena::automatic) {
  configureSocket(socket_, Side::accepts, deadPeerMs, kMaxBatchBytes);
  makeServer(socket_, credentials);
  socket_.set(zmq::sockopt::rcvhwm, 256);
  socket_.bind(bindEndpoint);
  port_ = portOf(lastEndpoint(socket_));
  thread_ = std::thread([this] { run(); });
}

PieceReceiver::~PieceReceiver() {
  std::vector<std::uint64_t> sessions;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [session, attached] : attached_) sessions.push_back(session);
  }
  for (const std::uint64_t session : sessions) detach(session);
  stop_ = true;
  thread_.join();
}

void PieceReceiver::attach(std::uint64_t session, Codec codec, int renderRanks, WallNode* node) {
  std::lock_guard lock(mutex_);
  attached_[session] = {codec, renderRanks, node, 0};
  logged_.clear();
}

void PieceReceiver::detach(std::uint64_t session) {
  std::unique_lock lock(mutex_);
  const auto it = attached_.find(session);
  if (it == attached_.end()) return;
  it->second.node = nullptr;  // no new batch goes to it
  idle_.wait(lock, [&] { return it->second.inFlight == 0; });
  attached_.erase(it);
}

void PieceReceiver::logOnce(const std::string& peer, const std::string& what) {
  std::lock_guard lock(mutex_);
  const std::string key = peer + what.substr(0, 40);
  if (logged_.size() >= kMaxLogged || !logged_.insert(key).second) return;
  log_("dropped a message on the piece port from connection " + peer + ": " + what);
}

void PieceReceiver::run() {
  while (!stop_) {
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    zmq::poll(&item, 1, std::chrono::milliseconds(100));
    zmq::message_t id, body;
    while (!stop_ && socket_.recv(id, zmq::recv_flags::dontwait)) {
      // A ROUTER message is [peer id][body]; a peer that sends several frames gets the rest
      // dropped with the first.
      if (!id.more() || !socket_.recv(body, zmq::recv_flags::dontwait)) continue;
      const std::string peer = hex(id);
      while (body.more()) {
        zmq::message_t extra;
        if (!socket_.recv(extra, zmq::recv_flags::dontwait)) break;
        body.swap(extra);
        logOnce(peer, "a message of several parts");
      }
      try {
        handle(peer, std::move(body));
      } catch (const std::exception& e) {
        logOnce(peer, e.what());  // e.g. a task arena that cannot take more work
      }
    }
  }
}

void PieceReceiver::handle(std::string peer, zmq::message_t message) {
  const auto* data = static_cast<const std::byte*>(message.data());
  std::uint64_t session = 0;
  try {
    const MessageHeader h = parseHeader(data, message.size());
    if (h.kind != static_cast<std::uint16_t>(Kind::Batch))
      throw base::Error("message kind " + std::to_string(h.kind) + " is not a piece batch");
    session = h.session;
  } catch (const std::exception& e) {
    logOnce(peer, e.what());
    return;
  }
  WallNode* node = nullptr;
  Codec codec;
  int renderRanks = 0;
  {
    std::lock_guard lock(mutex_);
    const auto it = session == 0 ? attached_.end() : attached_.find(session);
    if (it != attached_.end() && it->second.node) {
      node = it->second.node;
      codec = it->second.codec;
      renderRanks = it->second.renderRanks;
      ++it->second.inFlight;
    }
  }
  if (!node) {
    logOnce(peer, "not of a connected job's session");
    return;
  }
  auto work = std::make_shared<zmq::message_t>(std::move(message));
  arena_.enqueue([this, work, session, node, codec, renderRanks, peer] {
    const auto* bytes = static_cast<const std::byte*>(work->data());
    std::vector<BatchPiece> pieces;
    std::string sender = "connection " + peer;
    try {
      const BatchHeader h = parseBatch(bytes, work->size(), pieces);
      if (h.codec != codec) throw base::Error("a batch in another codec than the job's");
      if (h.renderRank >= static_cast<std::uint32_t>(renderRanks))
        throw base::Error("a batch from render rank " + std::to_string(h.renderRank) + " of " +
                          std::to_string(renderRanks));
      sender = "render rank " + std::to_string(h.renderRank);
      for (const BatchPiece& p : pieces) {
        const bool ok = node->receivePiece(
            sender, h.frameId, h.display, p.local,
            [&](Image& image) {
              decodePixels(
                  codec, p.data, p.size, p.local.width(), p.local.height(),
                  image.pixels.data() + static_cast<size_t>(p.local.y0) * image.width + p.local.x0,
                  image.width);
            },
            p.size + kPieceRecordBytes);
        if (!ok) break;  // the node has the error: it ends the job
      }
    } catch (const std::exception& e) {
      // A malformed batch with the session's id: the job is broken; the node ends it.
      node->reportError(sender + ": " + e.what());
      logOnce(peer, e.what());
    }
    std::lock_guard lock(mutex_);
    // Still there: detach() waits for this before it erases the session.
    if (--attached_.at(session).inFlight == 0) idle_.notify_all();
  });
}

}  // namespace wall::service
