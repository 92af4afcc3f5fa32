// ConnectionWatch (wall/service/protocol/ConnectionWatch.h) on real sockets over loopback TCP: a
// ROUTER learns, by routing id, which of its peers' connections closed, and a new connection
// that gets a closed one's descriptor is not taken for it.
#include <gtest/gtest.h>

#include <chrono>

#include "wall/service/protocol/ConnectionWatch.h"
#include "wall/service/protocol/Zmq.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;

class ConnectionWatchTest : public ::testing::Test {
 protected:
  ConnectionWatchTest() {
    router.set(zmq::sockopt::rcvtimeo, 5000);
    router.bind("tcp://127.0.0.1:*");
  }
  zmq::socket_t dealer() {
    zmq::socket_t d(context, zmq::socket_type::dealer);
    d.set(zmq::sockopt::linger, 0);
    d.connect(lastEndpoint(router));
    return d;
  }
  // `d` says something; the router takes it and tells the watch. Its routing id.
  std::string says(zmq::socket_t& d) {
    d.send(zmq::str_buffer("hello"), zmq::send_flags::none);
    zmq::message_t id, body;
    EXPECT_TRUE(router.recv(id));
    EXPECT_TRUE(router.recv(body));
    const std::string peer(static_cast<const char*>(id.data()), id.size());
    watch.heard(peer, body);
    return peer;
  }
  // What closed, once something did (5 s at most).
  std::vector<std::string> closed() {
    const auto until = Clock::now() + std::chrono::seconds(5);
    std::vector<std::string> out;
    while (out.empty() && Clock::now() < until) {
      zmq::pollitem_t item = watch.pollItem();
      zmq::poll(&item, 1, std::chrono::milliseconds(100));
      out = watch.closed();
    }
    return out;
  }

  zmq::context_t context;
  zmq::socket_t router{context, zmq::socket_type::router};
  ConnectionWatch watch{context, router};  // before the router binds
};

TEST_F(ConnectionWatchTest, NamesEachPeerWhoseConnectionClosed) {
  zmq::socket_t a = dealer(), b = dealer();
  const std::string idA = says(a), idB = says(b);
  says(a);  // a second message on the same connection changes nothing
  EXPECT_TRUE(watch.closed().empty());

  a.close();
  EXPECT_EQ(closed(), std::vector<std::string>{idA});
  // The next connection most likely gets a's descriptor: it is not a, and a's close is not its.
  zmq::socket_t c = dealer();
  const std::string idC = says(c);
  EXPECT_NE(idC, idA);
  EXPECT_TRUE(watch.closed().empty());
  says(b);
  EXPECT_TRUE(watch.closed().empty());

  b.close();
  EXPECT_EQ(closed(), std::vector<std::string>{idB});
  c.close();
  EXPECT_EQ(closed(), std::vector<std::string>{idC});
}

TEST_F(ConnectionWatchTest, AConnectionThatSentNothingIsNotReported) {
  zmq::socket_t silent = dealer(), talker = dealer();
  const std::string id = says(talker);
  silent.close();  // connected, never a message: no routing id the router's owner knows
  talker.close();
  EXPECT_EQ(closed(), std::vector<std::string>{id});
  EXPECT_TRUE(watch.closed().empty());
}

}  // namespace
}  // namespace wall::service
