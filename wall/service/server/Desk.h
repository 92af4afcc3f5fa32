#pragma once
// The head of a service wall: wall process 0's desk thread, which owns the directory socket
// (`--listen`) that render jobs say hello to and the other wall processes join
// (docs/service.md, "A wall that stays up"; wall/service/protocol/Protocol.h and
// LinkMessages.h).
//
// For jobs: one at a time (a second is refused as busy, or queued with `wait`), their keepalives,
// captures and goodbye, their credits, and the end of a job that goes silent or whose connection
// closes (at once: wall/service/protocol/ConnectionWatch.h).
// For the wall's processes: who is in the wall (Join, Beat), the commands of a job to every
// process in it, its swap barriers and capture gathers. A process that stops answering (dies,
// hangs, its link is cut) is dropped after the timeout: the barriers go on without it, the job
// is told (Roster) and stops sending its displays' pieces. When it joins again during a job it
// is given the job (Start) from the first frame the job cannot have started without knowing it
// is back (the credit rule: frame F starts once F - K is presented), and the job a new roster.
//
// The head's own process reaches the desk in process, through ProcessLink.
//
// Three parts: Membership (who is in the wall) and JobDesk (the jobs and each process's seat in
// them) decide, with no socket and no clock of their own; the desk is the loop around them: the
// socket, the thread, decoding messages and carrying out what the two decide.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "wall/layout/Layout.h"
#include "wall/service/server/JobDesk.h"
#include "wall/service/server/ProcessLink.h"
#include "wall/service/server/WallService.h"

namespace wall::service {

class Desk : public ProcessLink {
 public:
  struct Setup {
    const Layout* layout = nullptr;
    ServiceOptions options;
    std::string ownEndpoint;  // process 0's piece socket
    // Commands for the head's own process, called on the desk thread.
    std::function<void(const ServiceCommand&)> deliver;
  };
  explicit Desk(Setup setup);
  ~Desk() override;  // ends the desk thread
  Desk(const Desk&) = delete;
  Desk& operator=(const Desk&) = delete;

  // Binds the directory socket; throws base::Error naming --listen on a bad address or a port in
  // use. Returns the endpoint bound (with the real port).
  std::string bind(const std::string& endpoint);
  void start();
  // Thread-safe: the processes (1..W-1) not in the wall now.
  std::vector<int> absentProcesses() const;
  // The desk thread ended (after the wall's shutdown was sent to every process).
  bool closed() const;
  // Thread-safe: moves and resizes job `session`'s window to `window` on the canvas
  // (JobDesk::reshape); waits for the desk's verdict.
  JobDesk::MoveVerdict reshape(std::uint64_t session, const dfb::Region& window);

  // The window manager (serve --control), thread-safe. The jobs' windows as of the desk's last
  // turn (at most 100 ms ago); a raise or a close is carried out on the desk thread before it
  // returns (false: no job of that number is on the wall). Throws base::Error when the desk
  // does not answer within a few seconds (it stopped).
  std::vector<JobDesk::Window> windows() const;
  bool raise(std::uint64_t number);
  bool close(std::uint64_t number, const std::string& why);
  // Job `number`'s window moved and resized to `window` (reshape() of its session; the verdict
  // says UnknownWindow when no job of that number is on the wall).
  JobDesk::MoveVerdict moveWindow(std::uint64_t number, const dfb::Region& window);

  std::uint64_t epoch() const override { return 0; }
  void toHead(const ServiceCommand& command, std::uint64_t epoch) override;
  void agreeMax(std::uint64_t epoch, std::uint64_t session, std::uint32_t frameId,
                std::int64_t* values, int count, Clock::time_point deadline) override;
  std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint64_t epoch, std::uint64_t session,
                                                        std::uint32_t frameId,
                                                        std::vector<std::uint32_t> mine,
                                                        Clock::time_point deadline) override;
  void presented(std::uint64_t session, std::uint32_t frameId, std::int64_t completeNs) override;
  void thumbnail(std::uint64_t session, const ThumbnailPart& part) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wall::service
