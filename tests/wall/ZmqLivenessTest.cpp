// configureSocket (wall/service/protocol/Zmq.h) on real sockets over loopback TCP: an accepting
// socket outlives a peer that fills its queue and then resets the connection (libzmq 4.3.4 aborts
// the process when a socket's own heartbeat timer fires on such a connection: docs/security.md,
// "A flooding peer and libzmq's heartbeats"). That a stopped peer is still dropped is
// tests/apps/wall_survives_test.sh's SIGSTOP step.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "wall/service/protocol/Zmq.h"

namespace wall::service {
namespace {

using namespace std::chrono_literals;

constexpr int kDeadPeerMs = 400;  // heartbeats every 100 ms on a dialing socket

class ZmqLivenessTest : public ::testing::Test {
 protected:
  ZmqLivenessTest() {
    configureSocket(router, Side::accepts, kDeadPeerMs, 1 << 20);
    router.set(zmq::sockopt::rcvhwm, 10);
    router.set(zmq::sockopt::rcvtimeo, 5000);
    router.bind("tcp://127.0.0.1:*");
  }
  // One message from a peer: its routing id and body.
  std::pair<std::string, std::string> receive() {
    zmq::message_t id, body;
    EXPECT_TRUE(router.recv(id));
    EXPECT_TRUE(router.recv(body));
    return {id.to_string(), body.to_string()};
  }

  zmq::context_t context;
  zmq::socket_t router{context, zmq::socket_type::router};
};

TEST_F(ZmqLivenessTest, AcceptingSocketOutlivesAFloodThatEndsInAReset) {
  {
    zmq::context_t floodContext;
    zmq::socket_t flood(floodContext, zmq::socket_type::dealer);
    flood.set(zmq::sockopt::sndhwm, 100000);
    flood.set(zmq::sockopt::rcvhwm, 1);  // what the router sends stays in its kernel buffer
    flood.set(zmq::sockopt::linger, 0);
    flood.connect(lastEndpoint(router));
    const std::string garbage(1000, 'x');
    for (int i = 0; i < 20000; ++i)
      (void)flood.send(zmq::buffer(garbage), zmq::send_flags::dontwait);
    std::this_thread::sleep_for(500ms);  // the router's queue for it is full: it stopped reading
    const std::string peer = receive().first;
    const std::string answer(1 << 16, 'y');
    for (int i = 0; i < 100; ++i) {
      if (!router.send(zmq::buffer(peer), zmq::send_flags::sndmore | zmq::send_flags::dontwait))
        break;
      (void)router.send(zmq::buffer(answer), zmq::send_flags::dontwait);
    }
    std::this_thread::sleep_for(500ms);
    // Closing with unread bytes in its receive buffer makes the kernel reset the connection.
  }
  // Several heartbeat intervals with the broken connection still queued.
  std::this_thread::sleep_for(std::chrono::milliseconds(3 * kDeadPeerMs));
  int drained = 0;
  router.set(zmq::sockopt::rcvtimeo, 200);
  for (zmq::message_t part; router.recv(part);) ++drained;
  EXPECT_GT(drained, 0);

  // A new peer is served.
  router.set(zmq::sockopt::rcvtimeo, 5000);
  zmq::socket_t good(context, zmq::socket_type::dealer);
  configureSocket(good, Side::dials, kDeadPeerMs, 1 << 20);
  good.connect(lastEndpoint(router));
  good.send(zmq::str_buffer("hello"), zmq::send_flags::none);
  EXPECT_EQ(receive().second, "hello");
}

}  // namespace
}  // namespace wall::service
