#include "wall/service/security/Gatekeeper.h"

#include <vector>

namespace wall::service {
namespace {
constexpr std::size_t kMaxLogged = 64;  // addresses whose refusals are logged
constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";

std::string text(const zmq::message_t& m) { return std::string(m.data<char>(), m.size()); }

// A peer's address as the log shows it: printable and short, whatever arrived.
std::string printable(const std::string& s) {
  std::string out;
  for (char c : s.substr(0, 64)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return out;
}
}  // namespace

Gatekeeper::Gatekeeper(zmq::context_t& context, const Credentials& credentials, Log log)
    : socket_(context, zmq::socket_type::rep),
      token_(credentials.token),
      clientKey_(credentials.secretKey.empty() ? std::string()
                                               : clientKeys(credentials.token).publicKey),
      log_(std::move(log)) {
  socket_.set(zmq::sockopt::linger, 0);
  socket_.bind(kZapEndpoint);
  thread_ = std::thread([this] { run(); });
}

Gatekeeper::~Gatekeeper() {
  stop_ = true;
  thread_.join();
}

bool Gatekeeper::admits(const std::string& mechanism,
                        const std::vector<zmq::message_t>& credentials) const {
  if (mechanism == "PLAIN" && clientKey_.empty() && credentials.size() == 2)
    return sameSecret(text(credentials[1]), token_);
  if (mechanism == "CURVE" && !clientKey_.empty() && credentials.size() == 1)
    return sameSecret(text(credentials[0]), clientKey_);
  return false;
}

void Gatekeeper::run() {
  while (!stop_) {
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    if (zmq::poll(&item, 1, std::chrono::milliseconds(100)) == 0) continue;
    // version, request id, domain, address, routing id, mechanism, credentials...
    std::vector<zmq::message_t> request;
    do {
      request.emplace_back();
      if (!socket_.recv(request.back(), zmq::recv_flags::none)) break;
    } while (request.back().more());
    if (request.size() < 6) continue;  // not a ZAP request; REP needs no answer to drop it
    const std::string address = text(request[3]), mechanism = text(request[5]);
    const std::vector<zmq::message_t> credentials(std::make_move_iterator(request.begin() + 6),
                                                  std::make_move_iterator(request.end()));
    const bool ok = text(request[0]) == "1.0" && text(request[2]) == "dfbwall" &&
                    admits(mechanism, credentials);
    if (!ok) {
      ++refused_;
      if (log_ && logged_.size() < kMaxLogged && logged_.insert(address).second)
        log_("refused a connection from " + printable(address) + " at the handshake: " +
             (mechanism == "CURVE" || mechanism == "PLAIN" ? "not the wall's token"
                                                           : "no credentials") +
             " (further refusals from there are not logged)");
    }
    const std::string status = ok ? "200" : "400";
    const std::string statusText = ok ? "OK" : "not the wall's token";
    const std::string user = ok ? "dfbwall" : "";
    socket_.send(zmq::str_buffer("1.0"), zmq::send_flags::sndmore);
    socket_.send(request[1], zmq::send_flags::sndmore);
    socket_.send(zmq::buffer(status), zmq::send_flags::sndmore);
    socket_.send(zmq::buffer(statusText), zmq::send_flags::sndmore);
    socket_.send(zmq::buffer(user), zmq::send_flags::sndmore);
    socket_.send(zmq::str_buffer(""), zmq::send_flags::none);
  }
}

}  // namespace wall::service
