#include "wall/service/server/Membership.h"

#include <algorithm>

#include "wall/service/protocol/PeerText.h"

namespace wall::service {

std::string durationText(std::chrono::milliseconds t) {
  const long long ms = t.count();
  return ms % 1000 == 0 ? std::to_string(ms / 1000) + " s" : std::to_string(ms) + " ms";
}

Membership::Membership(Setup setup, Clock::time_point now)
    : s_(std::move(setup)),
      beatEvery_(std::clamp<std::chrono::milliseconds>(
          s_.timeout / 4, std::chrono::milliseconds(50), std::chrono::milliseconds(1000))),
      lastBeat_(now),
      members_(static_cast<size_t>(std::max(1, s_.processCount))) {
  members_[0].live = true;
  members_[0].endpoint = s_.headEndpoint;
  members_[0].host = "the head";
}

std::string Membership::who(int process) const {
  return "wall process " + std::to_string(process) + " on " + peerText(member(process).host);
}

std::vector<int> Membership::absent() const {
  std::vector<int> out;
  for (int p = 1; p < processCount(); ++p)
    if (!live(p)) out.push_back(p);
  return out;
}

int Membership::liveMembers() const {
  int n = 0;
  for (int p = 1; p < processCount(); ++p) n += live(p) ? 1 : 0;
  return n;
}

int Membership::processOf(const std::string& peer) const {
  for (int p = 1; p < processCount(); ++p)
    if (live(p) && member(p).peer == peer) return p;
  return -1;
}

Membership::Verdict Membership::check(const Join& join) const {
  Verdict v;
  const int count = processCount();
  if (!s_.token.empty() && join.token != s_.token)
    v.problem = join.token.empty() ? "this wall needs a token (--token)" : "wrong token";
  else if (join.process < 1 || join.process >= static_cast<std::uint32_t>(count))
    v.problem = "the layout has wall processes 0.." + std::to_string(count - 1) + "; process " +
                std::to_string(join.process) +
                (join.process == 0 ? " is the head, which does not join" : " is not one of them");
  else if (join.layoutHash != s_.layoutHash)
    v.problem = "its layout is not the wall's (" + s_.layoutFile +
                "): every process must run the same displays";
  if (!v.problem.empty()) return v;
  const Member& m = member(static_cast<int>(join.process));
  v.outcome = m.live && m.incarnation == join.incarnation ? Verdict::Outcome::Again
                                                          : Verdict::Outcome::Joins;
  v.replaces = v.outcome == Verdict::Outcome::Joins && m.live;
  return v;
}

void Membership::admit(const std::string& peer, const Join& join, Clock::time_point now) {
  Member& m = members_[join.process];
  m.live = true;
  m.peer = peer;
  m.incarnation = join.incarnation;
  m.host = join.host;
  m.endpoint = join.pieceEndpoint;
  m.lastHeard = now;
}

void Membership::heard(int process, Clock::time_point now) {
  members_[static_cast<size_t>(process)].lastHeard = now;
}

bool Membership::drop(int process) {
  Member& m = members_[static_cast<size_t>(process)];
  if (process == 0 || !m.live) return false;
  m.live = false;
  return true;
}

bool Membership::beatDue(Clock::time_point now) {
  if (now - lastBeat_ < beatEvery_) return false;
  lastBeat_ = now;
  return true;
}

std::vector<Membership::Silent> Membership::silent(Clock::time_point now) const {
  std::vector<Silent> out;
  for (int p = 1; p < processCount(); ++p)
    if (live(p) && now - member(p).lastHeard > s_.timeout)
      out.push_back({p, "no word from it for " + durationText(s_.timeout)});
  return out;
}

}  // namespace wall::service
