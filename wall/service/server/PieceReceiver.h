#pragma once
// A service wall process's piece socket: every render rank of each connected job sends it the
// batches of this process's displays (wall/service/protocol/Protocol.h). One thread receives;
// batches of an attached session (one per job on the wall; each batch names its session) are
// decoded and handed to that job's wall node (WallNode::receivePiece)
// on a TBB arena, several at once, as the messenger does with MPI pieces. Anything else — another
// session's batch, a malformed message, a stranger — is dropped and logged (one line per peer
// connection and kind of problem), never an error of the wall.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include <tbb/task_arena.h>

#include "wall/display/WallNode.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/security/Gatekeeper.h"

namespace wall::service {

class PieceReceiver {
 public:
  using Log = std::function<void(const std::string&)>;
  // Binds a ROUTER socket to `bindEndpoint` ("tcp://ADDR:PORT", port 0 or * for any) and starts
  // receiving; only peers with `credentials` get through its handshake. `handlerThreads`:
  // decoding threads (0: the cores). `deadPeerMs`: heartbeat bound.
  PieceReceiver(const std::string& bindEndpoint, const Credentials& credentials, int handlerThreads,
                int deadPeerMs, Log log);
  ~PieceReceiver();
  PieceReceiver(const PieceReceiver&) = delete;
  PieceReceiver& operator=(const PieceReceiver&) = delete;

  int port() const { return port_; }

  // From now on batches of `session` go to `node`: their codec must be `codec`, their render
  // rank below `renderRanks`. Other sessions attached stay so.
  void attach(std::uint64_t session, Codec codec, int renderRanks, WallNode* node);
  // No batch of `session` reaches its node any more once this returns (it waits for those being
  // decoded).
  void detach(std::uint64_t session);

 private:
  void run();
  void handle(std::string peer, zmq::message_t message);
  void logOnce(const std::string& peer, const std::string& what);

  zmq::context_t context_{1};
  Gatekeeper gatekeeper_;
  zmq::socket_t socket_;
  int port_ = 0;
  Log log_;
  tbb::task_arena arena_;
  std::mutex mutex_;
  std::condition_variable idle_;
  struct Attached {
    Codec codec = Codec::Raw;
    int renderRanks = 0;
    WallNode* node = nullptr;
    int inFlight = 0;  // batches being decoded
  };
  std::map<std::uint64_t, Attached> attached_;  // by session
  std::set<std::string> logged_;                // peer + problem, bounded
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace wall::service
