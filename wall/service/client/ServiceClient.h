#pragma once
// A render job's side of a persistent wall (`dfbwall serve`, wall/service/server/WallService.h).
//
// ServiceClient, on render rank 0 only: says hello to the wall's directory socket and gets the
// directory (or a refusal: a token refused at the handshake, busy, another protocol version),
// then keeps the job alive (a keepalive every second: the wall drops a job it has not heard from
// within its timeout), turns the wall's Presented messages into frame credits
// (wall/route/FrameCredits.h), and tells the wall about captures and the last frame.
//
// ServicePieceSink, on every render rank: the display-routing op's pieces for a service wall,
// encoded with the job's codec into one batch per (display, frame), sent to the wall process
// that drives the display when the rank's frame is done (or when a batch grows past a few MiB).
#include <mpi.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "wall/route/FrameCredits.h"
#include "wall/route/PieceSink.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/security/Credentials.h"

namespace wall::service {

class ServiceClient {
 public:
  // Connects to "HOST:PORT" with `credentials` and waits up to `timeout` for the directory.
  // With hello.wait, a busy wall queues the job: `onQueued(text)` is told, and the wait for the
  // directory starts over each time the wall says where the job stands. Throws base::Error with
  // the wall's reason, a handshake the wall refused (the token) or that cannot complete (the
  // pinned key), or "no dfbwall wall answered at HOST:PORT within S s".
  ServiceClient(const std::string& address, const Credentials& credentials, const Hello& hello,
                std::chrono::milliseconds timeout,
                const std::function<void(const std::string&)>& onQueued = {});
  ~ServiceClient();  // says goodbye if bye() was not called (the wall drops the job at once)
  ServiceClient(const ServiceClient&) = delete;
  ServiceClient& operator=(const ServiceClient&) = delete;

  const Directory& directory() const { return directory_; }
  const Credentials& credentials() const { return credentials_; }
  // The directory as the wall sent it (for the job's other ranks: parseDirectory).
  const messaging::Bytes& directoryBytes() const { return directoryBytes_; }

  // The link's thread runs from the directory on (keepalives: a job that sets up for longer
  // than the wall's timeout is not dropped). start() hands it the credits to fill and `onError`
  // to report a wall that ends the job (Ended: its reason) or goes silent for its timeout
  // before the last frame's credit (on the link's thread; also what failed before start();
  // call it once).
  void start(FrameCredits& credits, std::function<void(const std::string&)> onError);
  // Thread-safe. Capture frame `frameId` (or the first after it), request `sequence`.
  void capture(std::uint32_t frameId, std::uint64_t sequence);
  // Thread-safe. The job's last frame: the wall presents up to it and then ends the job.
  void bye(std::uint32_t lastFrame);
  // Thread-safe. The newest roster the wall sent (wall processes lost or back), packed, and its
  // version (0: the directory's). The link reads a roster before any later credit, so the roster
  // a frame starts with is never older than the one the wall counted on (Protocol.h, Roster).
  std::uint32_t rosterVersion() const;
  messaging::Bytes rosterBytes() const;
  // Thread-safe. The newest move of the job's window the wall sent (Protocol.h, Reshape): its
  // version (0: none) and switch frame, and the message (for the job's other ranks). The link
  // reads a reshape before any later credit, so the frame it switches at cannot have started.
  struct ReshapeNews {
    std::uint32_t version = 0, fromFrame = 0;
  };
  ReshapeNews reshapeNews() const;
  messaging::Bytes reshapeBytes() const;
  // Thread-safe. Where the wall's key and mouse events over the job's window go (called on the
  // link's thread; none: they are dropped). docs/service.md, "Several jobs at once".
  void onInput(std::function<void(const WindowInput&)> handler);
  // Thread-safe, also from the input handler: the size of the window the wall's events come in
  // (the directory's, then the newest move's: the wall sends a move before any event in the new
  // window's pixels).
  struct Size {
    int width = 0, height = 0;
  };
  Size windowSize() const;

 private:
  void run();
  void post(messaging::Bytes message);

  std::string address_;
  Credentials credentials_;
  zmq::context_t context_{1};
  zmq::socket_t socket_;
  Directory directory_;
  std::atomic<std::uint64_t> windowSize_{0};  // width << 32 | height: read whole, never torn
  void setWindowSize(const Layout& window);
  messaging::Bytes directoryBytes_;
  FrameCredits* credits_ = nullptr;                  // set by start(), under mutex_
  std::function<void(const std::string&)> onError_;  // set by start(), under mutex_
  mutable std::mutex mutex_;
  std::vector<messaging::Bytes> outbox_;
  bool byeSent_ = false;
  std::uint32_t lastFrame_ = 0;  // named by bye()
  std::uint32_t rosterVersion_ = 0;
  messaging::Bytes rosterBytes_;
  ReshapeNews reshape_;
  messaging::Bytes reshapeBytes_;
  std::function<void(const WindowInput&)> onInput_;
  Waker waker_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Collective over `comm` (a render job's ranks): `client` (non-null on rank 0 of `comm` only)
// read the wall's directory; every rank gets it (bounded by `timeout`).
Directory shareDirectory(MPI_Comm comm, const ServiceClient* client,
                         std::chrono::milliseconds timeout);
// Collective over `comm`: the credentials `client` (non-null on rank 0 of `comm` only) connected
// with, on every rank (for their piece sockets; bounded by `timeout`).
Credentials shareCredentials(MPI_Comm comm, const ServiceClient* client,
                             std::chrono::milliseconds timeout);
// Collective over `comm`, when the roster version a frame order carries is new to the ranks:
// the roster `client` (rank 0 of `comm` only) has, on every rank (bounded by `timeout`).
Roster shareRoster(MPI_Comm comm, const ServiceClient* client, std::chrono::milliseconds timeout);
// Collective over `comm`, when the reshape version a frame order carries is new to the ranks: the
// move `client` (rank 0 of `comm` only) has, on every rank (bounded by `timeout`).
Reshape shareReshape(MPI_Comm comm, const ServiceClient* client, std::chrono::milliseconds timeout);
// The hello of a job of `renderRanks` ranks on this host (its token is checked at the handshake,
// not in the hello).
Hello jobHello(int renderRanks, int tileSize, const CodecSpec& codec, int framesInFlight, bool wait,
               const std::string& captureDir, int captureEvery);

// Every render rank: DEALER sockets to the wall processes' piece sockets (connected at once;
// ZeroMQ queues until they are up).
class ServicePieceSink : public PieceSink {
 public:
  ServicePieceSink(const Directory& directory, const Credentials& credentials, int renderRank,
                   const CodecSpec& codec, int deadPeerMs);
  ~ServicePieceSink() override;
  std::size_t send(std::uint32_t frameId, int display, const dfb::Region& local,
                   const std::uint32_t* pixels, int stride) override;
  void endFrame(std::uint32_t frameId) override;
  bool otherHost(int) const override { return true; }
  // Between frames (no send in progress): the wall processes pieces go to from the next frame
  // on. A lost process's pieces are dropped here and counted (what its socket still held is
  // discarded); a process back (restarted) gets a fresh socket. Throws base::Error when the roster
  // does not fit the directory.
  void setRoster(const Roster& roster);
  // Pieces not sent since the last call: their wall process was lost, or took nothing for the
  // timeout.
  std::uint64_t takeDropped() { return dropped_.exchange(0); }
  // Bytes and messages handed to the sockets since the last call.
  struct Traffic {
    std::uint64_t bytes = 0, messages = 0;
  };
  Traffic takeTraffic() { return {wireBytes_.exchange(0), messages_.exchange(0)}; }

 private:
  struct Batch {
    std::mutex mutex;
    BatchWriter writer;
    std::uint32_t frameId = 0;
    bool open = false;
  };
  void flush(int display, Batch& batch);  // with batch.mutex held

  std::uint64_t session_;
  Credentials credentials_;
  int renderRank_;
  CodecSpec codec_;
  std::vector<int> processOfDisplay_;
  zmq::context_t context_{1};
  void connect(size_t process, const std::string& endpoint);  // with its socket mutex held
  void sendBounded(size_t process, messaging::Bytes bytes, std::uint32_t pieces);

  int deadPeerMs_;
  int sendWaitMs_;  // the longest a batch waits for a full queue: the wall's timeout
  std::vector<zmq::socket_t> sockets_;  // by wall process
  std::vector<std::string> endpoints_;
  std::vector<std::unique_ptr<std::mutex>> socketMutex_;
  std::unique_ptr<std::atomic<bool>[]> live_;    // by wall process
  std::vector<std::unique_ptr<Batch>> batches_;  // by display
  std::atomic<std::uint64_t> wireBytes_{0}, messages_{0}, dropped_{0};
};

}  // namespace wall::service
