#pragma once
// A service wall process other than the head: its link to the head's directory socket
// (wall/service/protocol/LinkMessages.h). It joins (again and again until welcomed: the head may
// not be up yet, or be restarting), sends a beat every quarter of the timeout, hands the head's
// commands to the process, and carries the process's swap barriers, capture pixels and answers.
//
// The beats also say the process's presenting thread is alive (mainAlive): a link whose process
// hangs goes quiet, and the head drops it as it drops a dead one.
//
// When the head goes silent for the timeout (it died, hangs, or the link is cut) or says this
// process was dropped (it hung longer than the timeout, e.g. SIGSTOP), the link is lost:
// `onLost` tells the process to give its job up, and the link joins again on a fresh socket with
// a new incarnation, so nothing of the old one (queued beats, a stale barrier) reaches the head.
#include <functional>
#include <memory>
#include <string>

#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/security/Credentials.h"
#include "wall/service/server/ProcessLink.h"

namespace wall::service {

class MemberLink : public ProcessLink {
 public:
  struct Setup {
    std::string head;         // HOST:PORT of the head's directory socket (--join)
    Join join;                // process, host, piece endpoint, layout hash
    Credentials credentials;  // the wall's token (and its public key, with CURVE)
    std::chrono::milliseconds timeout{60000};
    // On the link thread: a command of the head; the link was lost (why).
    std::function<void(const ServiceCommand&)> deliver;
    std::function<void(const std::string&)> onLost;
    std::function<void(const std::string&)> log;
  };
  explicit MemberLink(Setup setup);
  ~MemberLink() override;
  MemberLink(const MemberLink&) = delete;
  MemberLink& operator=(const MemberLink&) = delete;

  void start();
  // Until joined (true), refused by the head (throws base::Error with its reason), or `until`.
  bool waitUntilJoined(Clock::time_point until);
  bool joined() const;
  // Non-empty once the head refused this process (its token at the handshake, another layout):
  // fatal.
  std::string refusal() const;
  // Thread-safe: the process's presenting thread is alive. The link beats only while it was
  // last called within the timeout, so a process whose presenting thread hangs (a driver) is
  // dropped by the head like a dead one.
  void mainAlive();

  std::uint64_t epoch() const override;
  void toHead(const ServiceCommand& command, std::uint64_t epoch) override;
  void agreeMax(std::uint64_t epoch, std::uint64_t session, std::uint32_t frameId,
                std::int64_t* values, int count, Clock::time_point deadline) override;
  std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint64_t epoch, std::uint64_t session,
                                                        std::uint32_t frameId,
                                                        std::vector<std::uint32_t> mine,
                                                        Clock::time_point deadline) override;
  void presented(std::uint64_t, std::uint32_t, std::int64_t) override {}
  void thumbnail(std::uint64_t session, const ThumbnailPart& part) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wall::service
