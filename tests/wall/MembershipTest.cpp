// Who is in a service wall (wall/service/server/Membership.h): joins checked and told apart,
// beats due, silence after the timeout, drops. The time is the test's.
#include <gtest/gtest.h>

#include "wall/service/server/Membership.h"

namespace wall::service {
namespace {

using Clock = Membership::Clock;
using namespace std::chrono_literals;
using Outcome = Membership::Verdict::Outcome;
const Clock::time_point t0{std::chrono::hours(1)};
constexpr std::uint64_t kLayoutHash = 0x1234;

Membership threeProcesses() {
  return Membership({3, "t", kLayoutHash, "walls/3x1.toml", "tcp://head:1", 600ms}, t0);
}

Join joinOf(std::uint32_t process, std::uint64_t incarnation = 1) {
  Join j;
  j.token = "t";
  j.process = process;
  j.host = "host" + std::to_string(process);
  j.pieceEndpoint = "tcp://host" + std::to_string(process) + ":9";
  j.layoutHash = kLayoutHash;
  j.incarnation = incarnation;
  return j;
}

TEST(Membership, OnlyTheHeadIsInTheWallAtFirst) {
  const Membership members = threeProcesses();
  EXPECT_TRUE(members.live(0));
  EXPECT_EQ(members.member(0).endpoint, "tcp://head:1");
  EXPECT_EQ(members.absent(), (std::vector<int>{1, 2}));
  EXPECT_EQ(members.liveMembers(), 0);
  EXPECT_EQ(members.who(0), "wall process 0 on the head");
}

TEST(Membership, AJoinWithAWrongTokenLayoutOrProcessIsRefusedWithTheReason) {
  const Membership members = threeProcesses();
  Join j = joinOf(1);
  j.token = "wrong";
  EXPECT_EQ(members.check(j).outcome, Outcome::Refused);
  EXPECT_EQ(members.check(j).problem, "wrong token");
  j.token.clear();
  EXPECT_EQ(members.check(j).problem, "this wall needs a token (--token)");

  j = joinOf(1);
  j.layoutHash ^= 1;
  EXPECT_EQ(members.check(j).problem,
            "its layout is not the wall's (walls/3x1.toml): every process must run the same "
            "displays");
  EXPECT_EQ(members.check(joinOf(0)).problem,
            "the layout has wall processes 0..2; process 0 is the head, which does not join");
  EXPECT_EQ(members.check(joinOf(3)).problem,
            "the layout has wall processes 0..2; process 3 is not one of them");
  EXPECT_EQ(members.check(joinOf(2)).outcome, Outcome::Joins);
  EXPECT_TRUE(members.check(joinOf(2)).problem.empty());
}

TEST(Membership, ARepeatedJoinIsTheSameProcessAndARestartReplacesIt) {
  Membership members = threeProcesses();
  members.admit("link-a", joinOf(1, 7), t0);
  EXPECT_EQ(members.processOf("link-a"), 1);
  EXPECT_EQ(members.absent(), std::vector<int>{2});
  EXPECT_EQ(members.who(1), "wall process 1 on host1");

  // The same incarnation again: it missed the Welcome.
  const Membership::Verdict again = members.check(joinOf(1, 7));
  EXPECT_EQ(again.outcome, Outcome::Again);
  EXPECT_FALSE(again.replaces);

  // A new incarnation while the old one is live: it restarted; the old one goes first.
  const Membership::Verdict restart = members.check(joinOf(1, 8));
  EXPECT_EQ(restart.outcome, Outcome::Joins);
  EXPECT_TRUE(restart.replaces);
  EXPECT_TRUE(members.drop(1));
  members.admit("link-b", joinOf(1, 8), t0);
  EXPECT_EQ(members.processOf("link-a"), -1);
  EXPECT_EQ(members.processOf("link-b"), 1);
  EXPECT_EQ(members.member(1).incarnation, 8u);

  // Once dropped, the same incarnation joins anew (no replacement).
  EXPECT_TRUE(members.drop(1));
  const Membership::Verdict back = members.check(joinOf(1, 8));
  EXPECT_EQ(back.outcome, Outcome::Joins);
  EXPECT_FALSE(back.replaces);
}

TEST(Membership, AMemberSilentForTheTimeoutIsNamedUntilDroppedOnce) {
  Membership members = threeProcesses();
  members.admit("link-1", joinOf(1), t0);
  members.admit("link-2", joinOf(2), t0);
  EXPECT_TRUE(members.silent(t0 + 600ms).empty());  // the timeout, not more
  members.heard(1, t0 + 500ms);
  const auto silent = members.silent(t0 + 601ms);
  ASSERT_EQ(silent.size(), 1u);
  EXPECT_EQ(silent[0].process, 2);
  EXPECT_EQ(silent[0].why, "no word from it for 600 ms");
  EXPECT_TRUE(members.drop(2));
  EXPECT_FALSE(members.drop(2));  // once
  EXPECT_FALSE(members.drop(0));  // the head is never dropped
  EXPECT_TRUE(members.silent(t0 + 601ms).empty());
  EXPECT_EQ(members.absent(), std::vector<int>{2});
  EXPECT_EQ(members.liveMembers(), 1);
  EXPECT_EQ(members.member(2).host, "host2");  // kept for the logs of its loss
}

TEST(Membership, BeatsAreDueEveryQuarterOfTheTimeout) {
  Membership members = threeProcesses();
  EXPECT_FALSE(members.beatDue(t0 + 100ms));
  EXPECT_TRUE(members.beatDue(t0 + 150ms));
  EXPECT_FALSE(members.beatDue(t0 + 299ms));
  EXPECT_TRUE(members.beatDue(t0 + 300ms));
  // Bounded: at most every second however long the timeout.
  Membership slow({2, "", 0, "f", "e", std::chrono::minutes(1)}, t0);
  EXPECT_TRUE(slow.beatDue(t0 + 1s));
}

TEST(Membership, DurationsReadAsTheLogsSayThem) {
  EXPECT_EQ(durationText(5000ms), "5 s");
  EXPECT_EQ(durationText(600ms), "600 ms");
}

}  // namespace
}  // namespace wall::service
