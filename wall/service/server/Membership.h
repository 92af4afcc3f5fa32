#pragma once
// Who is in a service wall (wall/service/server/Desk.h): the head's record of the wall's
// processes, each with its link (the ZeroMQ routing id it joined from), incarnation, host, piece
// endpoint and the last time it was heard. It checks joins (token, process number, layout),
// tells a repeated join (a lost Welcome) from a restart, says when to beat and who has been
// silent for the timeout. Bookkeeping only: no sockets, no threads, no clock (the time is
// passed in); what a loss or a return means for the running job is JobDesk's.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "wall/service/protocol/LinkMessages.h"

namespace wall::service {

// "5 s", "600 ms": a timeout as the logs say it.
std::string durationText(std::chrono::milliseconds t);

class Membership {
 public:
  using Clock = std::chrono::steady_clock;
  struct Setup {
    int processCount = 1;
    std::string token;  // what a joining process must present (empty: none)
    std::uint64_t layoutHash = 0;
    std::string layoutFile;    // for the refusal of another layout
    std::string headEndpoint;  // process 0's piece socket
    std::chrono::milliseconds timeout{60000};
  };
  struct Member {
    bool live = false;
    std::string peer;  // ZeroMQ routing id of its link
    std::uint64_t incarnation = 0;
    std::string host, endpoint;
    Clock::time_point lastHeard;
  };

  // Process 0, the head, is always live; the others are absent until they join.
  Membership(Setup setup, Clock::time_point now);

  int processCount() const { return static_cast<int>(members_.size()); }
  const Member& member(int process) const { return members_[static_cast<size_t>(process)]; }
  bool live(int process) const { return member(process).live; }
  // "wall process 2 on wall2", for logs and the job's roster messages.
  std::string who(int process) const;
  std::vector<int> absent() const;               // processes 1..W-1 not in the wall
  int liveMembers() const;                       // live processes besides the head
  int processOf(const std::string& peer) const;  // a live process's number, or -1

  // What a Join means: refused (with the reason), the same incarnation again (it missed the
  // Welcome), or a process that joins; `replaces` when that process is live under an older
  // incarnation (it restarted), which the desk drops before calling admit.
  struct Verdict {
    enum class Outcome { Refused, Again, Joins } outcome = Outcome::Refused;
    std::string problem;
    bool replaces = false;
  };
  Verdict check(const Join& join) const;
  void admit(const std::string& peer, const Join& join, Clock::time_point now);
  void heard(int process, Clock::time_point now);
  // False when the process was not live.
  bool drop(int process);

  // Every quarter of the timeout (50 ms..1 s), true once: the desk beats every live member.
  bool beatDue(Clock::time_point now);
  struct Silent {
    int process = 0;
    std::string why;
  };
  // Live members not heard for longer than the timeout.
  std::vector<Silent> silent(Clock::time_point now) const;

 private:
  Setup s_;
  std::chrono::milliseconds beatEvery_;
  Clock::time_point lastBeat_;
  std::vector<Member> members_;
};

}  // namespace wall::service
