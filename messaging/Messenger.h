#pragma once
// Asynchronous point-to-point messaging between distributed objects (paper, section 3.2).
//
// An object registers a handler under a global id on every rank that takes part; a message goes
// to (rank, id). The MPI thread owns every MPI call on the messenger's own duplicated
// communicator (non-blocking send, matched probe, receive, test) and backs off when idle instead
// of spinning; it hands what it received to the inbox thread. The inbox thread takes every
// message waiting at once and hands each to its handler: messages for objects that accept them
// concurrently (tile inputs, wall pieces) go to a TBB task arena, several decompressed and
// handled at once, as OSPRay hands its messages to its tasking system; the others are handled on
// the inbox thread one at a time. Messages to one's own rank never touch MPI.
//
// Contracts:
//  - send() is thread-safe and never blocks on the network; the messenger owns the payload.
//  - A handler whose concurrent() is false runs on the inbox thread only, serially, and sees its
//    messages in arrival order (per sender: send order). One whose concurrent() is true may run
//    on several threads at once and sees its messages in any order. Either way, every message
//    received before one for a serial handler is handled before it, and every one received
//    after it, after it. A handler may send.
//  - A message to an id not registered on the receiver is an error reported through the error
//    callback with both ids and counted; it never crashes and is never dropped silently.
//    Register on every rank before anyone sends (a collective constructor does that).
//  - quiesce() and stop() are collective over the communicator; leave() is not: it tells every
//    other rank this one is gone for good, and their quiesce(), and waits whose Bound asks
//    departed(), fail at once instead of at their deadline.
//  - A messenger destroyed without stop() while an exception unwinds the stack is abandoned:
//    no collective (another rank may never join one), its threads end at once, and buffers
//    still on the wire are left to MPI. The process is expected to end soon (MPI_Abort).
#include <mpi.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "messaging/Compression.h"
#include "messaging/Envelope.h"

namespace messaging {

class MessageHandler {
 public:
  virtual ~MessageHandler() = default;
  virtual void incoming(int fromRank, Bytes&& payload) = 0;
  // True when incoming() may run on several threads at once and in any order of arrival.
  virtual bool concurrent() const { return false; }
};

struct MessengerOptions {
  bool compress = true;
  // Between ranks on one host, shared memory moves bytes faster than Snappy shrinks them
  // (measured on the wall: 1.2-1.45x more frames per second uncompressed), so by default only
  // messages that leave the host are compressed.
  bool compressWithinHost = false;
  // Payloads smaller than this go raw: Snappy costs more than it saves on tiny messages.
  std::size_t compressMinBytes = 2048;
  // Longest sleep of an idle MPI thread; bounds the added receive latency.
  std::chrono::microseconds maxIdleSleep{200};
  std::chrono::microseconds restingSleep{10000};  // see setResting
  // The messenger's collectives give up with a base::DeadlineError after this long: the start-up
  // exchange in the constructor, quiesce() and stop().
  std::chrono::milliseconds quiesceTimeout{30000};
  // Threads that decompress and handle messages for concurrent handlers at once, the inbox
  // thread included (a TBB arena; its workers come from the process's TBB pool, so a cap on
  // TBB's parallelism caps these too). 0: TBB's default (the cores); 1: the inbox thread alone.
  int handlerThreads = 0;
  // The largest payload a message may carry (before compression), on both sides: send() refuses
  // a larger one, and one received that announces more is an error reported through the error
  // callback, so a corrupt 20-byte header cannot allocate 4 GiB. At most kLargestPayload (an
  // MPI count is an int); the same on every rank.
  std::size_t maxMessageBytes = std::size_t{1} << 30;
};

struct MessengerCounters {
  std::uint64_t messagesSent = 0, messagesReceived = 0, messagesHandled = 0;
  std::uint64_t rawBytesSent = 0, wireBytesSent = 0;  // wire: after compression, with header
  std::uint64_t rawBytesReceived = 0, wireBytesReceived = 0;
  std::uint64_t messagesCompressed = 0;
  std::uint64_t unknownReceiver = 0, handlerErrors = 0;
  // Passes of the MPI thread's loop. An idle pass ends in a sleep of at least the current idle
  // sleep (unless something is sent), so an idle second has at most 1 s / maxIdleSleep of them
  // (restingSleep when resting) plus the back-off's ramp, however loaded the machine: what an
  // idle messenger costs, counted rather than timed.
  std::uint64_t mpiThreadWakeups = 0;
};

class Messenger {
 public:
  using ErrorCallback = std::function<void(const std::string&)>;

  // Collective over `comm`, which it duplicates (twice: point-to-point traffic and its own
  // collectives never share a communicator with the caller's collectives). The exchange of host
  // names is bounded by quiesceTimeout (a base::DeadlineError); the communicator splits before it
  // have no non-blocking form (docs/design.md, "Deadlines").
  explicit Messenger(MPI_Comm comm, MessengerOptions options = {});
  ~Messenger();  // stop()s if still running (collective then too), unless unwinding (above).
  Messenger(const Messenger&) = delete;
  Messenger& operator=(const Messenger&) = delete;

  int rank() const;
  int size() const;

  void registerObject(ObjectId id, MessageHandler* handler);
  // Waits for handler calls in progress on other threads to finish first (called from inside a
  // handler, it does not wait).
  void unregisterObject(ObjectId id);

  // A payload with this much spare capacity (reserve(size + kSpareCapacity)) goes out without
  // being copied.
  static constexpr std::size_t kSpareCapacity = kEnvelopeBytes;
  // Throws base::Error, sending nothing, for a payload above maxMessageBytes (the receiver's
  // cap). A send that MPI refuses later is reported through the error callback.
  void send(int toRank, ObjectId id, Bytes payload);
  // Whether `rank` shares this rank's host (MPI_COMM_TYPE_SHARED), and whether a message to it
  // is compressed (so a producer can choose a pre-filter that only pays before compression).
  bool sameHost(int rank) const;
  bool compresses(int toRank) const;
  // A hint that nothing is expected for a while (the application idles: a converged wall): the
  // MPI thread's idle sleeps may then grow to `restingSleep` instead of maxIdleSleep, so an idle
  // rank uses (nearly) no CPU. Sending wakes the thread at once as always; the first message
  // received ends the rest (it is found within one resting sleep).
  void setResting(bool resting);
  // The host `rank` runs on (MPI_Get_processor_name, exchanged at construction).
  const std::string& hostOf(int rank) const;
  // For an error about a deadline: asks every other rank for a sign of life (answered by its
  // inbox thread, whatever its main thread waits for) and waits up to `wait` for the answers.
  // From inside a handler it returns at once with nothing (the answers would wait for it).
  // Returns the ranks that did not answer, with their hosts ("rank 5 (wall1)"), comma-separated;
  // empty when all did. A stopped rank, or one behind a cut link, is found this way.
  std::string probePeers(std::chrono::milliseconds wait);

  // Returns once every message sent by any rank before it entered quiesce() (and every message
  // those sent while being handled) has been handled. Throws base::Error on timeout.
  void quiesce();
  // quiesce(), then joins both threads. Idempotent.
  void stop();
  // Instead of stop(), without a collective (a program that leaves before the others): sends
  // every other rank a "leave" message, waits (up to 1 s) until MPI has taken them, and ends
  // both threads. The messenger is stopped afterwards; its communicators are left to MPI.
  void leave();
  // The first peer that left (leave()), as "rank R (HOST) left ...", or empty. Thread-safe.
  std::string departed() const;

  MessengerCounters counters() const;
  // Traffic of one distributed object between ranks, on the wire (after compression, headers
  // included): what this rank sent to that id on other ranks, and what it received for it, in
  // bytes and in MPI messages (one per send(), however large: nothing is cut into fragments).
  // Only ids registered on this rank count what they receive (an unknown id is an error, not an
  // entry), so the table stays as small as the objects.
  struct ObjectTraffic {
    std::uint64_t bytesSent = 0, bytesReceived = 0;
    std::uint64_t messagesSent = 0, messagesReceived = 0;
  };
  ObjectTraffic traffic(ObjectId id) const;
  // Default: print to stderr with the rank.
  void setErrorCallback(ErrorCallback callback);

 private:
  void abandonThreads();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Registers `handler` under `id` for its lifetime (unregisters first thing in its destructor, so
// declare it after the handler it registers).
class Registration {
 public:
  Registration(Messenger& messenger, ObjectId id, MessageHandler* handler)
      : messenger_(messenger), id_(id) {
    messenger_.registerObject(id_, handler);
  }
  ~Registration() { messenger_.unregisterObject(id_); }
  Registration(const Registration&) = delete;
  Registration& operator=(const Registration&) = delete;

 private:
  Messenger& messenger_;
  ObjectId id_;
};

}  // namespace messaging
