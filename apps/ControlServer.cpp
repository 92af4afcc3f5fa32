#include "apps/ControlServer.h"

#include <fcntl.h>
#include <ifaddrs.h>
#include <microhttpd.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <arpa/inet.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <unordered_map>

namespace app {
namespace {

using Clock = std::chrono::steady_clock;

// Every request, from its connection's first byte (or the end of the request before on a
// kept-alive connection) to the last byte of its reply.
constexpr auto kRequestDeadline = std::chrono::seconds(5);
constexpr unsigned kMaxConnections = 256, kMaxConnectionsPerAddress = 128;
constexpr unsigned kEventThreads = 2;
constexpr size_t kConnectionMemory = 32 * 1024;  // a request's line and headers must fit

// The name to put in a URL for `host` (brackets around IPv6 addresses).
std::string urlHost(const std::string& host) {
  return host.find(':') == std::string::npos ? host : "[" + host + "]";
}

bool isWildcard(const std::string& host) { return host == "0.0.0.0" || host == "::"; }

// What a Host header may name when the server listens on every interface: this host's name and
// addresses.
std::vector<std::string> ownNames() {
  std::vector<std::string> names;
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) == 0 && name[0]) names.emplace_back(name);
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) == 0) {
    for (const ifaddrs* a = list; a; a = a->ifa_next) {
      if (!a->ifa_addr) continue;
      char text[INET6_ADDRSTRLEN] = {};
      if (a->ifa_addr->sa_family == AF_INET)
        ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(a->ifa_addr)->sin_addr, text,
                    sizeof text);
      else if (a->ifa_addr->sa_family == AF_INET6)
        ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(a->ifa_addr)->sin6_addr, text,
                    sizeof text);
      if (text[0]) names.emplace_back(text);
    }
    ::freeifaddrs(list);
  }
  return names;
}

// A listening socket on host:port (0: any free port); returns it and sets `bound` to the port.
int listenOn(const std::string& address, const std::string& host, int port, int& bound) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (const int code = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &found); code != 0)
    throw std::runtime_error("--control " + address + ": cannot resolve " + host + ": " +
                             ::gai_strerror(code));
  std::string problem;
  int fd = -1;
  for (const addrinfo* a = found; a && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    const int on = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 128) != 0) {
      problem = std::strerror(errno);
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(found);
  if (fd < 0)
    throw std::runtime_error("--control " + address + ": cannot listen on " + host + " port " +
                             service + ": " + problem +
                             " (in use, or not an address of this host)");
  sockaddr_storage local{};
  socklen_t length = sizeof local;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length);
  bound = ntohs(local.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&local)->sin6_port
                                            : reinterpret_cast<sockaddr_in*>(&local)->sin_port);
  return fd;
}

// One request being read: its body, kept up to one byte past the limit (ControlRequests then
// answers 413).
struct Reading {
  std::string body;
};

MHD_Result collect(void* cls, MHD_ValueKind, const char* key, const char* value) {
  static_cast<std::vector<std::pair<std::string, std::string>>*>(cls)->emplace_back(
      key ? key : "", value ? value : "");
  return MHD_YES;
}

}  // namespace

struct ControlServer::Impl {
  std::string host;
  int port = 0;
  ControlSecret secret;
  std::unique_ptr<ControlRequests> requests;
  int listenFd = -1;
  MHD_Daemon* daemon = nullptr;

  // The open connections and when their current request started; the reaper cuts the late.
  struct Open {
    int fd = -1;
    Clock::time_point since;
    bool cut = false;
  };
  std::mutex mutex;
  std::condition_variable wake;
  bool stopping = false;
  std::unordered_map<MHD_Connection*, Open> open;
  std::thread reaper;

  void reap();
  static MHD_Result answer(void* cls, MHD_Connection* connection, const char* url,
                           const char* method, const char* version, const char* upload,
                           size_t* uploadSize, void** state);
  static void completed(void* cls, MHD_Connection* connection, void** state,
                        MHD_RequestTerminationCode);
  static void connectionEvent(void* cls, MHD_Connection* connection, void** socketState,
                              MHD_ConnectionNotificationCode code);
};

ControlServer::ControlServer(const std::string& address, ControlSecret secret,
                             std::vector<std::string> hosts)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const size_t colon = address.rfind(':');
  m.host = colon == std::string::npos ? "127.0.0.1" : address.substr(0, colon);
  const std::string port = colon == std::string::npos ? address : address.substr(colon + 1);
  if (m.host.size() > 2 && m.host.front() == '[' && m.host.back() == ']')
    m.host = m.host.substr(1, m.host.size() - 2);
  int value = -1;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (ec != std::errc() || end != port.data() + port.size() || value < 0 || value > 65535 ||
      m.host.empty())
    throw std::runtime_error("--control " + address +
                             ": expected [ADDR:]PORT with a port in 0..65535, e.g. 8080 or "
                             "0.0.0.0:8080");
  m.listenFd = listenOn(address, m.host, value, m.port);
  m.secret = std::move(secret);
  hosts.push_back(m.host);
  if (isWildcard(m.host))
    for (std::string& name : ownNames()) hosts.push_back(std::move(name));
  m.requests = std::make_unique<ControlRequests>(ControlAccess{m.secret.token, m.port, hosts});
}

ControlServer::~ControlServer() {
  stop();
  if (impl_->listenFd >= 0) ::close(impl_->listenFd);
}

const std::string& ControlServer::host() const { return impl_->host; }
int ControlServer::port() const { return impl_->port; }
const ControlSecret& ControlServer::secret() const { return impl_->secret; }
ControlRequests& ControlServer::requests() { return *impl_->requests; }

std::string ControlServer::startLine() const {
  const Impl& m = *impl_;
  // On every interface: the address that works on this host; other hosts use its name.
  const std::string address =
      "http://" + urlHost(isWildcard(m.host) ? "127.0.0.1" : m.host) + ":" + std::to_string(m.port);
  if (m.secret.generated) return "control API on " + address + "/?token=" + m.secret.token;
  return "control API on " + address + "/ (open " + address + "/?token=TOKEN, TOKEN from " +
         m.secret.source + ")";
}

std::string ControlServer::pageAddress(const std::string& thisHost) const {
  const Impl& m = *impl_;
  return "http://" + urlHost(isWildcard(m.host) ? thisHost : m.host) + ":" +
         std::to_string(m.port) + "/";
}

void ControlServer::start() {
  Impl& m = *impl_;
  const unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL;
  m.daemon = MHD_start_daemon(
      flags, 0, nullptr, nullptr, &Impl::answer, &m, MHD_OPTION_LISTEN_SOCKET, m.listenFd,
      MHD_OPTION_THREAD_POOL_SIZE, kEventThreads, MHD_OPTION_CONNECTION_LIMIT, kMaxConnections,
      MHD_OPTION_PER_IP_CONNECTION_LIMIT, kMaxConnectionsPerAddress, MHD_OPTION_CONNECTION_TIMEOUT,
      static_cast<unsigned>(std::chrono::seconds(kRequestDeadline).count()),
      MHD_OPTION_CONNECTION_MEMORY_LIMIT, kConnectionMemory, MHD_OPTION_NOTIFY_COMPLETED,
      &Impl::completed, &m, MHD_OPTION_NOTIFY_CONNECTION, &Impl::connectionEvent, &m,
      MHD_OPTION_END);
  if (!m.daemon)
    throw std::runtime_error("--control: libmicrohttpd could not start serving port " +
                             std::to_string(m.port));
  m.listenFd = -1;  // the daemon closes it
  m.reaper = std::thread([&m] { m.reap(); });
}

void ControlServer::stop() {
  Impl& m = *impl_;
  if (m.reaper.joinable()) {
    {
      std::lock_guard<std::mutex> lock(m.mutex);
      m.stopping = true;
    }
    m.wake.notify_all();
    m.reaper.join();
  }
  if (m.daemon) MHD_stop_daemon(m.daemon);
  m.daemon = nullptr;
}

void ControlServer::Impl::reap() {
  std::unique_lock<std::mutex> lock(mutex);
  while (!wake.wait_for(lock, std::chrono::milliseconds(200), [this] { return stopping; })) {
    const Clock::time_point late = Clock::now() - kRequestDeadline;
    for (auto& [connection, o] : open) {
      // The daemon closes the socket only after telling connectionEvent, which waits for this
      // lock: the descriptor is still this connection's. Its event loop sees the hang-up.
      if (!o.cut && o.since < late) {
        ::shutdown(o.fd, SHUT_RDWR);
        o.cut = true;
      }
    }
  }
}

void ControlServer::Impl::connectionEvent(void* cls, MHD_Connection* connection, void**,
                                          MHD_ConnectionNotificationCode code) {
  Impl& m = *static_cast<Impl*>(cls);
  std::lock_guard<std::mutex> lock(m.mutex);
  if (code == MHD_CONNECTION_NOTIFY_STARTED) {
    const MHD_ConnectionInfo* info =
        MHD_get_connection_info(connection, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (info) m.open[connection] = Open{info->connect_fd, Clock::now(), false};
  } else {
    m.open.erase(connection);
  }
}

void ControlServer::Impl::completed(void* cls, MHD_Connection* connection, void** state,
                                    MHD_RequestTerminationCode) {
  Impl& m = *static_cast<Impl*>(cls);
  delete static_cast<Reading*>(*state);
  *state = nullptr;
  // The next request on this connection has its own deadline.
  std::lock_guard<std::mutex> lock(m.mutex);
  if (const auto found = m.open.find(connection); found != m.open.end())
    found->second.since = Clock::now();
}

MHD_Result ControlServer::Impl::answer(void* cls, MHD_Connection* connection, const char* url,
                                       const char* method, const char*, const char* upload,
                                       size_t* uploadSize, void** state) {
  Impl& m = *static_cast<Impl*>(cls);
  if (!*state) {  // the headers are in; the body (if any) follows
    *state = new Reading;
    return MHD_YES;
  }
  Reading& reading = *static_cast<Reading*>(*state);
  if (*uploadSize) {
    const size_t room = kMaxControlBody + 1 - std::min(reading.body.size(), kMaxControlBody + 1);
    reading.body.append(upload, std::min(room, *uploadSize));
    *uploadSize = 0;
    return MHD_YES;
  }
  HttpRequest request;
  request.method = method;
  request.path = url;
  request.body = std::move(reading.body);
  MHD_get_connection_values(connection, MHD_HEADER_KIND, &collect, &request.headers);
  MHD_get_connection_values(connection, MHD_GET_ARGUMENT_KIND, &collect, &request.query);
  HttpReply reply;
  try {
    reply = m.requests->handle(request);
  } catch (const std::exception& e) {  // never through libmicrohttpd's C frames
    reply = HttpReply{500, "text/plain", std::string("the control server failed: ") + e.what(), {}};
  }
  MHD_Response* response = MHD_create_response_from_buffer(
      reply.body.size(), const_cast<char*>(reply.body.data()), MHD_RESPMEM_MUST_COPY);
  if (!response) return MHD_NO;
  MHD_add_response_header(response, MHD_HTTP_HEADER_CONTENT_TYPE, reply.contentType.c_str());
  for (const auto& [name, value] : reply.headers)
    MHD_add_response_header(response, name.c_str(), value.c_str());
  const MHD_Result queued =
      MHD_queue_response(connection, static_cast<unsigned>(reply.status), response);
  MHD_destroy_response(response);
  return queued;
}

}  // namespace app
