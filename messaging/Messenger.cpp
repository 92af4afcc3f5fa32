#include "messaging/Messenger.h"

#include <algorithm>
#include <array>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <shared_mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "base/Collectives.h"
#include "base/Error.h"
#include "base/ObjectIds.h"
#include "messaging/Envelope.h"

namespace messaging {
namespace {

constexpr int kTag = 7;
// The messenger's own objects: probePeers() asks, every rank's inbox thread answers.
constexpr ObjectId kProbeRequestObject =
    base::objectId(base::MessageObject::kMessengerProbeRequest);
constexpr ObjectId kProbeAnswerObject = base::objectId(base::MessageObject::kMessengerProbeAnswer);
// A rank that leaves without the collective stop() says so to every other rank (leave()).
constexpr ObjectId kLeaveObject = base::objectId(base::MessageObject::kMessengerLeave);

struct Packet {
  int rank;  // destination when outgoing, source when incoming
  Bytes wire;
};

using Clock = std::chrono::steady_clock;

// Handler calls in progress on this thread (any messenger's): unregisterObject() and
// probePeers() from inside a handler must not wait for handlers to finish.
thread_local int handlerDepth = 0;

}  // namespace

struct Messenger::Impl {
  Messenger* owner = nullptr;
  MPI_Comm p2p = MPI_COMM_NULL;
  MPI_Comm control = MPI_COMM_NULL;
  int rank = 0, size = 1;
  MessengerOptions options;
  std::vector<bool> sameHost;  // by rank of p2p
  std::vector<std::string> hosts;

  // probePeers(): the round asked for and who answered it (by rank).
  std::mutex probeMutex;
  std::condition_variable probeCv;
  std::uint64_t probeRound = 0;
  std::vector<bool> probeAnswered;
  void handleProbe(int fromRank, ObjectId object, const Bytes& payload);

  std::mutex outboxMutex;
  std::condition_variable outboxCv;
  std::vector<Packet> outbox;

  std::mutex inboxMutex;
  std::condition_variable inboxCv;
  std::deque<Packet> inbox;
  bool inboxBusy = false;

  std::mutex registryMutex;
  std::unordered_map<ObjectId, MessageHandler*> handlers;
  // Held shared while a handler runs, so unregister can wait for every call in progress.
  std::shared_mutex dispatchMutex;
  std::thread::id inboxThreadId;
  // Where concurrent handlers run (null: handlerThreads is 1). Made here, initialised by the
  // inbox thread on first use, so its tasks run with that thread's floating-point settings
  // (TBB arenas capture them): a tile input is combined the same way on whichever thread.
  std::unique_ptr<tbb::task_arena> arena;

  std::mutex errorMutex;
  ErrorCallback onError;

  // The first peer that left (leave() on its side), as departed() says it.
  mutable std::mutex departedMutex;
  std::string departed;

  std::atomic<bool> exitThreads{false};
  std::atomic<bool> resting{false};
  std::atomic<std::uint64_t> sendsInFlight{0};
  std::atomic<std::uint64_t> messagesSent{0}, messagesReceived{0}, messagesHandled{0},
      rawBytesSent{0}, wireBytesSent{0}, rawBytesReceived{0}, wireBytesReceived{0},
      messagesCompressed{0}, unknownReceiver{0}, handlerErrors{0}, mpiThreadWakeups{0};

  mutable std::mutex trafficMutex;
  std::unordered_map<ObjectId, ObjectTraffic> traffic;
  // What arrived for `id`, when an object is registered under it.
  void countReceived(ObjectId id, std::uint64_t bytes) {
    {
      std::lock_guard lock(registryMutex);
      if (!handlers.contains(id)) return;
    }
    countTraffic(id, 0, bytes);
  }
  void countTraffic(ObjectId id, std::uint64_t sent, std::uint64_t received) {
    std::lock_guard lock(trafficMutex);
    ObjectTraffic& t = traffic[id];
    t.bytesSent += sent;
    t.bytesReceived += received;
    t.messagesSent += sent > 0 ? 1 : 0;
    t.messagesReceived += received > 0 ? 1 : 0;
  }

  std::thread mpiThread, inboxThread;
  bool stopped = false;
  // Set when the messenger is abandoned during unwinding: the MPI thread leaves at once.
  std::atomic<bool> abandon{false};
  int uncaughtAtConstruction = 0;

  // Sets the exit flag under both queues' mutexes: a thread that checked its wait predicate
  // just before cannot miss the notification that follows.
  void signalExit() {
    {
      std::lock_guard outboxLock(outboxMutex);
      std::lock_guard inboxLock(inboxMutex);
      exitThreads = true;
    }
    outboxCv.notify_all();
    inboxCv.notify_all();
  }

  void report(const std::string& message) {
    std::lock_guard lock(errorMutex);
    if (onError)
      onError(message);
    else
      std::fprintf(stderr, "[rank %d] messaging: %s\n", rank, message.c_str());
  }

  void pushInbox(Packet packet) {
    {
      std::lock_guard lock(inboxMutex);
      inbox.push_back(std::move(packet));
    }
    inboxCv.notify_one();
  }

  // With MPI_ERRORS_RETURN a failed call comes back here; the error callback hears of it
  // (the app then ends the job). Returns whether the call succeeded.
  bool mpiOk(int code, const char* call, const std::string& context = {}) {
    if (code == MPI_SUCCESS) return true;
    try {
      base::checkMpi(code, call);
    } catch (const std::exception& e) {
      report(std::string("MPI thread: ") + e.what() + context);
    }
    return false;
  }

  void mpiLoop();
  void inboxLoop();
  bool isConcurrent(const Packet& packet);
  void handleTogether(std::vector<Packet*>& packets);
  void dispatch(Packet& packet);
  void waitLocallyIdle(Clock::time_point deadline);
};

void Messenger::Impl::mpiLoop() {
  std::vector<MPI_Request> sendRequests;
  std::vector<Bytes> sendBuffers;
  std::deque<MPI_Request> receiveRequests;  // in posting order, which is per-sender send order
  std::deque<Packet> receiveBuffers;
  std::vector<Packet> fresh;
  std::vector<int> done;
  auto idleSleep = std::chrono::microseconds(1);

  while (true) {
    mpiThreadWakeups++;
    bool active = false;
    {
      std::lock_guard lock(outboxMutex);
      fresh.swap(outbox);
    }
    for (Packet& packet : fresh) {
      // send() refused anything larger: the count fits an int.
      MPI_Request request = MPI_REQUEST_NULL;
      if (!mpiOk(MPI_Isend(packet.wire.data(), static_cast<int>(packet.wire.size()), MPI_BYTE,
                           packet.rank, kTag, p2p, &request),
                 "MPI_Isend",
                 " (a message of " + std::to_string(packet.wire.size()) + " bytes to rank " +
                     std::to_string(packet.rank) + ")")) {
        // Reported (the failure path); nothing to wait for, and the message never left.
        sendsInFlight--;
        messagesSent--;
        continue;
      }
      sendRequests.push_back(request);
      sendBuffers.push_back(std::move(packet.wire));
      active = true;
    }
    fresh.clear();

    if (!sendRequests.empty()) {
      int completed = 0;
      done.resize(sendRequests.size());
      mpiOk(MPI_Testsome(static_cast<int>(sendRequests.size()), sendRequests.data(), &completed,
                         done.data(), MPI_STATUSES_IGNORE),
            "MPI_Testsome");
      if (completed > 0 && completed != MPI_UNDEFINED) {
        size_t kept = 0;
        for (size_t i = 0; i < sendRequests.size(); ++i) {
          if (sendRequests[i] == MPI_REQUEST_NULL) continue;
          if (kept != i) {  // a self-move would free a buffer MPI is still sending from
            sendRequests[kept] = sendRequests[i];
            sendBuffers[kept] = std::move(sendBuffers[i]);
          }
          ++kept;
        }
        sendRequests.resize(kept);
        sendBuffers.resize(kept);
        sendsInFlight -= static_cast<std::uint64_t>(completed);
        active = true;
      }
    }

    for (;;) {
      int flag = 0;
      MPI_Message message;
      MPI_Status status;
      if (!mpiOk(MPI_Improbe(MPI_ANY_SOURCE, kTag, p2p, &flag, &message, &status), "MPI_Improbe") ||
          !flag)
        break;
      int count = 0;
      MPI_Get_count(&status, MPI_BYTE, &count);
      receiveBuffers.push_back(Packet{status.MPI_SOURCE, Bytes(static_cast<size_t>(count))});
      MPI_Request request;
      mpiOk(MPI_Imrecv(receiveBuffers.back().wire.data(), count, MPI_BYTE, &message, &request),
            "MPI_Imrecv");
      receiveRequests.push_back(request);
      active = true;
    }

    while (!receiveRequests.empty()) {
      int flag = 0;
      if (!mpiOk(MPI_Test(&receiveRequests.front(), &flag, MPI_STATUS_IGNORE), "MPI_Test") || !flag)
        break;
      Packet packet = std::move(receiveBuffers.front());
      receiveRequests.pop_front();
      receiveBuffers.pop_front();
      messagesReceived++;
      wireBytesReceived += packet.wire.size();

      if (packet.wire.size() >= kEnvelopeBytes)
        countReceived(peekEnvelope(packet.wire).object, packet.wire.size());
      // Before the handler can run: a handler may rest the messenger again (a heartbeat).
      resting = false;
      pushInbox(std::move(packet));
      active = true;
    }

    if (abandon) {
      // Nobody will wait for these any more; MPI may still read the buffers, so they are
      // handed over for good instead of freed.
      for (MPI_Request& r : sendRequests) MPI_Request_free(&r);
      for (MPI_Request& r : receiveRequests) MPI_Request_free(&r);
      static_cast<void>(new std::vector<Bytes>(std::move(sendBuffers)));
      static_cast<void>(new std::deque<Packet>(std::move(receiveBuffers)));
      return;
    }
    if (exitThreads && sendRequests.empty() && receiveRequests.empty()) {
      std::lock_guard lock(outboxMutex);
      if (outbox.empty()) break;
    }
    if (active) {
      idleSleep = std::chrono::microseconds(1);
    } else {
      // Ranks share cores: an idle MPI thread sleeps, longer the longer it stays idle, but a
      // new outgoing message wakes it at once.
      std::unique_lock lock(outboxMutex);
      outboxCv.wait_for(lock, idleSleep, [&] { return !outbox.empty() || exitThreads.load(); });
      idleSleep = std::min(idleSleep * 2, resting ? options.restingSleep : options.maxIdleSleep);
    }
  }
}

void Messenger::Impl::inboxLoop() {
  std::deque<Packet> batch;
  std::vector<Packet*> together;
  while (true) {
    {
      std::unique_lock lock(inboxMutex);
      inboxCv.wait(lock, [&] { return !inbox.empty() || exitThreads.load(); });
      if (inbox.empty() || abandon) return;
      batch.swap(inbox);  // every message waiting: the more, the more can be handled at once
      inboxBusy = true;
    }
    // Runs of messages for concurrent handlers are handled together; a message for a serial
    // handler waits for the run before it and is handled alone, here, before anything after it.
    for (Packet& packet : batch) {
      if (abandon) break;
      if (isConcurrent(packet)) {
        together.push_back(&packet);
        continue;
      }
      handleTogether(together);
      dispatch(packet);
      messagesHandled++;
    }
    if (!abandon) handleTogether(together);
    together.clear();
    batch.clear();
    std::lock_guard lock(inboxMutex);
    inboxBusy = false;
  }
}

bool Messenger::Impl::isConcurrent(const Packet& packet) {
  if (packet.wire.size() < kEnvelopeBytes) return false;  // dispatch() reports it
  const ObjectId object = peekEnvelope(packet.wire).object;
  std::lock_guard lock(registryMutex);
  auto found = handlers.find(object);
  return found != handlers.end() && found->second->concurrent();
}

void Messenger::Impl::handleTogether(std::vector<Packet*>& packets) {
  if (packets.size() > 1 && arena) {
    // The inbox thread joins the arena and works on the messages with its workers; each message
    // is isolated, so a thread waiting inside a handler (a nested parallel loop) never picks up
    // another message whose handler may need a lock the first one holds.
    arena->execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, packets.size(), 1),
                        [&](const tbb::blocked_range<size_t>& range) {
                          for (size_t i = range.begin(); i != range.end(); ++i) {
                            tbb::this_task_arena::isolate([&] { dispatch(*packets[i]); });
                            messagesHandled++;
                          }
                        });
    });
  } else {
    for (Packet* packet : packets) {
      dispatch(*packet);
      messagesHandled++;
    }
  }
  packets.clear();
}

void Messenger::Impl::dispatch(Packet& packet) {
  try {
    Bytes payload;
    const Envelope header = openEnvelope(std::move(packet.wire), options.maxMessageBytes, payload);
    rawBytesReceived += payload.size();
    if (header.object == kProbeRequestObject || header.object == kProbeAnswerObject) {
      handleProbe(packet.rank, header.object, payload);
      return;
    }
    if (header.object == kLeaveObject) {
      const std::string why = "rank " + std::to_string(packet.rank) + " (" +
                              hosts.at(static_cast<size_t>(packet.rank)) +
                              ") left without closing (it will not join again)";
      // Reported before departed() says so: whoever sees departed() (quiesce giving up) may
      // count on the error callback having been told.
      report(why);
      {
        std::lock_guard lock(departedMutex);
        if (departed.empty()) departed = why;
      }
      return;
    }

    std::shared_lock dispatching(dispatchMutex);
    MessageHandler* handler = nullptr;
    {
      std::lock_guard lock(registryMutex);
      auto found = handlers.find(header.object);
      if (found != handlers.end()) handler = found->second;
    }
    if (!handler) {
      unknownReceiver++;
      report("message from rank " + std::to_string(packet.rank) + " to object id " +
             std::to_string(header.object) + " on rank " + std::to_string(rank) +
             ", which has no object registered under that id; message discarded");
      return;
    }
    ++handlerDepth;
    struct Leave {
      ~Leave() { --handlerDepth; }
    } leave;
    handler->incoming(packet.rank, std::move(payload));
  } catch (const std::exception& e) {
    handlerErrors++;
    report("handling a message from rank " + std::to_string(packet.rank) + ": " + e.what());
  }
}

void Messenger::Impl::waitLocallyIdle(Clock::time_point deadline) {
  while (Clock::now() < deadline) {
    bool idle = sendsInFlight == 0;
    if (idle) {
      std::lock_guard lock(outboxMutex);
      idle = outbox.empty();
    }
    if (idle) {
      std::lock_guard lock(inboxMutex);
      idle = inbox.empty() && !inboxBusy;
    }
    if (idle) return;
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

Messenger::Messenger(MPI_Comm comm, MessengerOptions options) : impl_(std::make_unique<Impl>()) {
  if (options.maxMessageBytes > kLargestPayload)
    throw base::Error("messenger: a message limit of " + std::to_string(options.maxMessageBytes) +
                      " bytes is more than MPI can send in one message (" +
                      std::to_string(kLargestPayload) + ")");
  impl_->options = options;
  impl_->owner = this;
  impl_->uncaughtAtConstruction = std::uncaught_exceptions();
  const base::Bound joined{.until = options.quiesceTimeout,
                           .late = "starting the messenger: another rank did not join within " +
                                   std::to_string(options.quiesceTimeout.count()) + " ms"};
  base::checkMpi(MPI_Comm_dup(comm, &impl_->p2p), "MPI_Comm_dup");
  base::checkMpi(MPI_Comm_dup(comm, &impl_->control), "MPI_Comm_dup");
  // No traffic on the new communicators until every rank has made them: OpenMPI 4.1 can take
  // a fragment for a communicator that a rank is still making (it is in the lookup table, its
  // matching state not yet) on another thread's progress, such as a live messenger's, and
  // crashes there (a SEGV in mca_pml_ob1_recv_frag_callback_match, seen under ASan).
  base::barrier(comm, joined);
  MPI_Comm_rank(impl_->p2p, &impl_->rank);
  MPI_Comm_size(impl_->p2p, &impl_->size);
  MPI_Comm host;
  base::checkMpi(
      MPI_Comm_split_type(impl_->p2p, MPI_COMM_TYPE_SHARED, impl_->rank, MPI_INFO_NULL, &host),
      "MPI_Comm_split_type");
  MPI_Group hostGroup, allGroup;
  MPI_Comm_group(host, &hostGroup);
  MPI_Comm_group(impl_->p2p, &allGroup);
  int hostSize = 0;
  MPI_Comm_size(host, &hostSize);
  std::vector<int> hostRanks(static_cast<size_t>(hostSize)), inAll(static_cast<size_t>(hostSize));
  for (int i = 0; i < hostSize; ++i) hostRanks[static_cast<size_t>(i)] = i;
  MPI_Group_translate_ranks(hostGroup, hostSize, hostRanks.data(), allGroup, inAll.data());
  impl_->sameHost.assign(static_cast<size_t>(impl_->size), false);
  for (int r : inAll) impl_->sameHost[static_cast<size_t>(r)] = true;
  MPI_Group_free(&hostGroup);
  MPI_Group_free(&allGroup);
  MPI_Comm_free(&host);
  std::array<char, MPI_MAX_PROCESSOR_NAME> name = {};
  int length = 0;
  MPI_Get_processor_name(name.data(), &length);
  for (const auto& n : base::allgather(name, impl_->control, joined))
    impl_->hosts.emplace_back(n.data(), strnlen(n.data(), n.size()));
  const int handlerThreads =
      options.handlerThreads > 0 ? options.handlerThreads : tbb::info::default_concurrency();
  // One slot for the inbox thread, which joins the arena for every run of messages.
  if (handlerThreads > 1) impl_->arena = std::make_unique<tbb::task_arena>(handlerThreads, 1);
  impl_->mpiThread = std::thread([this] { impl_->mpiLoop(); });
  impl_->inboxThread = std::thread([this] { impl_->inboxLoop(); });
  impl_->inboxThreadId = impl_->inboxThread.get_id();
}

Messenger::~Messenger() {
  if (impl_->stopped) return;
  if (std::uncaught_exceptions() > impl_->uncaughtAtConstruction) {
    abandonThreads();
    return;
  }
  try {
    stop();
  } catch (const std::exception& e) {
    impl_->report(std::string("stopping: ") + e.what());
    abandonThreads();
  }
}

void Messenger::abandonThreads() {
  impl_->abandon = true;
  impl_->signalExit();
  if (impl_->mpiThread.joinable()) impl_->mpiThread.join();
  if (impl_->inboxThread.joinable()) impl_->inboxThread.join();
}

int Messenger::rank() const { return impl_->rank; }
int Messenger::size() const { return impl_->size; }

void Messenger::registerObject(ObjectId id, MessageHandler* handler) {
  std::lock_guard lock(impl_->registryMutex);
  if (!impl_->handlers.emplace(id, handler).second)
    throw base::Error("object id " + std::to_string(id) + " is already registered on rank " +
                      std::to_string(impl_->rank));
}

void Messenger::unregisterObject(ObjectId id) {
  {
    std::lock_guard lock(impl_->registryMutex);
    impl_->handlers.erase(id);
  }
  if (handlerDepth == 0) {
    std::unique_lock wait(impl_->dispatchMutex);
  }
}

void Messenger::send(int toRank, ObjectId id, Bytes payload) {
  if (toRank < 0 || toRank >= impl_->size)
    throw base::Error("send to rank " + std::to_string(toRank) + " of a messenger with " +
                      std::to_string(impl_->size) + " ranks");
  const size_t rawBytes = payload.size();
  checkPayloadSize(
      rawBytes, impl_->options.maxMessageBytes,
      "message to object id " + std::to_string(id) + " on rank " + std::to_string(toRank));
  const bool remote = toRank != impl_->rank;
  bool compressed = false;
  Bytes wire =
      sealEnvelope(std::move(payload), id,
                   compresses(toRank) && rawBytes >= impl_->options.compressMinBytes, &compressed);
  if (compressed) impl_->messagesCompressed++;

  impl_->messagesSent++;
  impl_->rawBytesSent += rawBytes;
  if (!remote) {
    impl_->pushInbox(Packet{toRank, std::move(wire)});
    return;
  }
  impl_->wireBytesSent += wire.size();
  impl_->countTraffic(id, wire.size(), 0);
  impl_->sendsInFlight++;
  {
    std::lock_guard lock(impl_->outboxMutex);
    impl_->outbox.push_back(Packet{toRank, std::move(wire)});
  }
  impl_->outboxCv.notify_one();
}

void Messenger::setResting(bool resting) { impl_->resting = resting; }

bool Messenger::sameHost(int rank) const { return impl_->sameHost.at(static_cast<size_t>(rank)); }

const std::string& Messenger::hostOf(int rank) const {
  return impl_->hosts.at(static_cast<size_t>(rank));
}

std::string Messenger::probePeers(std::chrono::milliseconds wait) {
  Impl& i = *impl_;
  // The inbox thread answers probes: asking from it would wait for itself.
  if (std::this_thread::get_id() == i.inboxThreadId || handlerDepth > 0 || i.exitThreads) return {};
  std::uint64_t round = 0;
  {
    std::lock_guard lock(i.probeMutex);
    round = ++i.probeRound;
    i.probeAnswered.assign(static_cast<size_t>(i.size), false);
    i.probeAnswered[static_cast<size_t>(i.rank)] = true;
  }
  for (int r = 0; r < i.size; ++r)
    if (r != i.rank) {
      Bytes ask(sizeof round);
      std::memcpy(ask.data(), &round, sizeof round);
      send(r, kProbeRequestObject, std::move(ask));
    }
  std::unique_lock lock(i.probeMutex);
  i.probeCv.wait_for(lock, wait, [&] {
    return std::all_of(i.probeAnswered.begin(), i.probeAnswered.end(), [](bool a) { return a; });
  });
  std::string silent;
  for (int r = 0; r < i.size; ++r)
    if (!i.probeAnswered[static_cast<size_t>(r)])
      silent += (silent.empty() ? "rank " : ", rank ") + std::to_string(r) + " (" + hostOf(r) + ")";
  return silent;
}

void Messenger::Impl::handleProbe(int fromRank, ObjectId object, const Bytes& payload) {
  std::uint64_t round = 0;
  if (payload.size() != sizeof round) throw base::Error("malformed probe");
  std::memcpy(&round, payload.data(), sizeof round);
  if (object == kProbeRequestObject) {
    owner->send(fromRank, kProbeAnswerObject, Bytes(payload));
    return;
  }
  {
    std::lock_guard lock(probeMutex);
    if (round == probeRound) probeAnswered.at(static_cast<size_t>(fromRank)) = true;
  }
  probeCv.notify_all();
}

bool Messenger::compresses(int toRank) const {
  return impl_->options.compress && toRank != impl_->rank &&
         (impl_->options.compressWithinHost || !sameHost(toRank));
}

void Messenger::quiesce() {
  const auto deadline = Clock::now() + impl_->options.quiesceTimeout;
  std::uint64_t previous[2] = {~0ull, ~0ull};
  // Counting termination detection: done when the global sent and handled totals agree, twice
  // in a row with the same values, so no message can hide between two ranks' snapshots.
  while (true) {
    impl_->waitLocallyIdle(deadline);
    // A collective cannot be cancelled: when a rank does not answer in time the reduction stays
    // posted and may still complete later, so its buffers live on the heap and are left to it
    // (a few bytes, once, on a path that ends in an error) rather than on this stack.
    auto* counts =
        new std::uint64_t[4]{impl_->messagesSent.load(), impl_->messagesHandled.load(), 0, 0};
    base::allreduce(counts, counts + 2, 2, MPI_UINT64_T, MPI_SUM, impl_->control,
                    {.until = deadline,
                     .late = "messaging did not quiesce within " +
                             std::to_string(impl_->options.quiesceTimeout.count()) +
                             " ms: another rank is not answering",
                     .unless = [this] { return departed(); }});
    const std::uint64_t global[2] = {counts[2], counts[3]};
    delete[] counts;
    if (global[0] == global[1] && global[0] == previous[0] && global[1] == previous[1]) return;
    previous[0] = global[0];
    previous[1] = global[1];
  }
}

void Messenger::leave() {
  Impl& i = *impl_;
  if (i.stopped) return;
  i.stopped = true;
  for (int r = 0; r < i.size; ++r)
    if (r != i.rank) send(r, kLeaveObject, Bytes{});
  // Small messages go eagerly: MPI has them once the MPI thread has posted them.
  const auto deadline = Clock::now() + std::chrono::seconds(1);
  while (i.sendsInFlight > 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  abandonThreads();
}

std::string Messenger::departed() const {
  std::lock_guard lock(impl_->departedMutex);
  return impl_->departed;
}

void Messenger::stop() {
  if (impl_->stopped) return;
  quiesce();
  impl_->stopped = true;
  impl_->signalExit();
  impl_->mpiThread.join();
  impl_->inboxThread.join();
  MPI_Comm_free(&impl_->p2p);
  MPI_Comm_free(&impl_->control);
}

MessengerCounters Messenger::counters() const {
  const Impl& i = *impl_;
  return {i.messagesSent,    i.messagesReceived, i.messagesHandled,   i.rawBytesSent,
          i.wireBytesSent,   i.rawBytesReceived, i.wireBytesReceived, i.messagesCompressed,
          i.unknownReceiver, i.handlerErrors,    i.mpiThreadWakeups};
}

Messenger::ObjectTraffic Messenger::traffic(ObjectId id) const {
  std::lock_guard lock(impl_->trafficMutex);
  auto found = impl_->traffic.find(id);
  return found == impl_->traffic.end() ? ObjectTraffic{} : found->second;
}

void Messenger::setErrorCallback(ErrorCallback callback) {
  std::lock_guard lock(impl_->errorMutex);
  impl_->onError = std::move(callback);
}

}  // namespace messaging
