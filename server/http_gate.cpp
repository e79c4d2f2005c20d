#include "server/http_gate.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>

namespace server {

using Clock = std::chrono::steady_clock;

namespace {

// Runs each accepted socket's task at once on httplib's accept thread: the task only hands the
// socket to the gate.
class InlineQueue final : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

bool header_complete(const std::string& bytes) {
  return bytes.find("\r\n\r\n") != std::string::npos;
}

// Waits until `fd` is ready for `events`, at most `timeout_ms`.
bool wait_ready(int fd, short events, int timeout_ms) {
  pollfd p{fd, events, 0};
  for (;;) {
    const int n = ::poll(&p, 1, timeout_ms);
    if (n < 0 && errno == EINTR) continue;
    return n > 0 && (p.revents & (events | POLLHUP | POLLERR)) != 0;
  }
}

int milliseconds(time_t sec, time_t usec) { return static_cast<int>(sec * 1000 + usec / 1000); }

void close_socket(int fd) {
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
}

void address_of(int fd, bool peer, std::string& ip, int& port) {
  sockaddr_storage addr{};
  socklen_t length = sizeof addr;
  auto* a = reinterpret_cast<sockaddr*>(&addr);
  if ((peer ? ::getpeername(fd, a, &length) : ::getsockname(fd, a, &length)) != 0) return;
  char host[NI_MAXHOST], service[NI_MAXSERV];
  if (::getnameinfo(a, length, host, sizeof host, service, sizeof service,
                    NI_NUMERICHOST | NI_NUMERICSERV) == 0) {
    ip = host;
    port = std::atoi(service);
  }
}

}  // namespace

struct GatedHttpServer::Connection {
  int fd = -1;
  std::string buffer;  // received, not yet processed (a header, maybe the start of a body)
  Clock::time_point deadline;
  std::size_t requests = 0;  // processed on this connection so far
};

// httplib's view of a connection on a worker: first the bytes the gate collected, then the
// socket, each wait bounded by the server's read or write timeout.
class GatedHttpServer::Stream final : public httplib::Stream {
 public:
  Stream(Connection& c, int read_ms, int write_ms)
      : c_(c), read_ms_(read_ms), write_ms_(write_ms) {}

  bool is_readable() const override {
    return pos_ < c_.buffer.size() || wait_ready(c_.fd, POLLIN, read_ms_);
  }
  bool is_writable() const override { return wait_ready(c_.fd, POLLOUT, write_ms_); }
  ssize_t read(char* ptr, size_t size) override {
    if (pos_ == c_.buffer.size()) {
      // refill: small reads (httplib reads lines a byte at a time) go through the buffer
      c_.buffer.clear();
      pos_ = 0;
      if (!wait_ready(c_.fd, POLLIN, read_ms_)) return -1;
      if (size >= kChunk) return receive(ptr, size);
      char chunk[kChunk];
      const ssize_t n = receive(chunk, sizeof chunk);
      if (n <= 0) return n;
      c_.buffer.assign(chunk, static_cast<size_t>(n));
    }
    const size_t n = std::min(size, c_.buffer.size() - pos_);
    std::memcpy(ptr, c_.buffer.data() + pos_, n);
    pos_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    for (;;) {
      const ssize_t n = ::send(c_.fd, ptr, size, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      return n;
    }
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    address_of(c_.fd, true, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    address_of(c_.fd, false, ip, port);
  }
  socket_t socket() const override { return c_.fd; }
  // drops what was consumed; the rest (a pipelined request) stays with the connection
  void keep_unread() {
    c_.buffer.erase(0, pos_);
    pos_ = 0;
  }

 private:
  static constexpr size_t kChunk = 4096;
  ssize_t receive(char* ptr, size_t size) {
    for (;;) {
      const ssize_t n = ::recv(c_.fd, ptr, size, 0);
      if (n < 0 && errno == EINTR) continue;
      return n;
    }
  }
  Connection& c_;
  size_t pos_ = 0;
  int read_ms_, write_ms_;
};

struct GatedHttpServer::Impl {
  explicit Impl(GateLimits l) : limits(l) {}

  void admit(Connection c);
  void run_gate();
  void on_readable(int fd);
  void close_expired();

  GatedHttpServer* server = nullptr;
  GateLimits limits;
  int epoll_fd = -1;
  int wake_fd = -1;
  mutable std::mutex mutex;
  std::map<int, Connection> waiting;  // by socket
  bool stopping = false;
  bool shut = false;
  std::thread gate;
  std::unique_ptr<httplib::ThreadPool> workers;
};

GatedHttpServer::GatedHttpServer(GateLimits limits) : impl_(std::make_unique<Impl>(limits)) {
  impl_->server = this;
  impl_->epoll_fd = ::epoll_create1(EPOLL_CLOEXEC);
  impl_->wake_fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (impl_->epoll_fd < 0 || impl_->wake_fd < 0) {
    throw std::system_error(errno, std::generic_category(), "HTTP gate: epoll");
  }
  epoll_event wake{};
  wake.events = EPOLLIN;
  wake.data.fd = impl_->wake_fd;
  ::epoll_ctl(impl_->epoll_fd, EPOLL_CTL_ADD, impl_->wake_fd, &wake);
  impl_->workers = std::make_unique<httplib::ThreadPool>(static_cast<size_t>(limits.workers));
  new_task_queue = [] { return new InlineQueue; };
  impl_->gate = std::thread([this] { impl_->run_gate(); });
}

GatedHttpServer::~GatedHttpServer() {
  shut_down();
  ::close(impl_->epoll_fd);
  ::close(impl_->wake_fd);
}

void GatedHttpServer::shut_down() {
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->shut) return;
    impl_->shut = true;
    impl_->stopping = true;
  }
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t ignored = ::write(impl_->wake_fd, &one, sizeof one);
  if (impl_->gate.joinable()) impl_->gate.join();
  impl_->workers->shutdown();  // requests in progress finish; their sockets are closed after
}

void GatedHttpServer::widen_listen_backlog() {
  const socket_t sock = svr_sock_;
  if (sock != INVALID_SOCKET) ::listen(sock, SOMAXCONN);  // Linux: updates a listening socket
}

std::size_t GatedHttpServer::waiting() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->waiting.size();
}

bool GatedHttpServer::process_and_close_socket(socket_t sock) {
  Connection c;
  c.fd = sock;
  c.deadline = Clock::now() + impl_->limits.header_timeout;
  impl_->admit(std::move(c));
  return true;
}

void GatedHttpServer::Impl::admit(Connection c) {
  std::unique_lock lock(mutex);
  if (!stopping && header_complete(c.buffer)) {
    lock.unlock();
    auto shared = std::make_shared<Connection>(std::move(c));
    workers->enqueue([this, shared] { server->serve(std::move(*shared)); });
    return;
  }
  if (stopping || waiting.size() >= limits.max_waiting) {
    close_socket(c.fd);
    return;
  }
  const int fd = c.fd;
  waiting.emplace(fd, std::move(c));
  epoll_event e{};
  e.events = EPOLLIN | EPOLLRDHUP;
  e.data.fd = fd;
  if (::epoll_ctl(epoll_fd, EPOLL_CTL_ADD, fd, &e) != 0) {
    waiting.erase(fd);
    close_socket(fd);
  }
}

void GatedHttpServer::Impl::run_gate() {
  epoll_event events[64];
  for (;;) {
    const int n = ::epoll_wait(epoll_fd, events, 64, 100);
    {
      std::lock_guard lock(mutex);
      if (stopping) break;
    }
    for (int i = 0; i < n; ++i) {
      if (events[i].data.fd == wake_fd) continue;
      on_readable(events[i].data.fd);
    }
    close_expired();
  }
  std::lock_guard lock(mutex);
  for (auto& [fd, c] : waiting) close_socket(fd);
  waiting.clear();
}

void GatedHttpServer::Impl::on_readable(int fd) {
  std::unique_lock lock(mutex);
  const auto it = waiting.find(fd);
  if (it == waiting.end()) return;
  Connection& c = it->second;
  bool ended = false;
  char chunk[4096];
  while (!header_complete(c.buffer) && c.buffer.size() <= kMaxHeaderBytes) {
    const ssize_t n = ::recv(fd, chunk, sizeof chunk, MSG_DONTWAIT);
    if (n > 0) {
      c.buffer.append(chunk, static_cast<size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      ended = n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK);
      break;
    }
  }
  const bool complete = header_complete(c.buffer);
  if (!complete && !ended && c.buffer.size() <= kMaxHeaderBytes) return;  // wait for more
  ::epoll_ctl(epoll_fd, EPOLL_CTL_DEL, fd, nullptr);
  Connection ready = std::move(c);
  waiting.erase(it);
  lock.unlock();
  if (complete) {
    admit(std::move(ready));
    return;
  }
  if (!ended) {
    static constexpr char kTooLarge[] =
        "HTTP/1.1 431 Request Header Fields Too Large\r\nConnection: close\r\n"
        "Content-Length: 0\r\n\r\n";
    [[maybe_unused]] const ssize_t sent =
        ::send(fd, kTooLarge, sizeof kTooLarge - 1, MSG_NOSIGNAL | MSG_DONTWAIT);
  }
  close_socket(fd);
}

void GatedHttpServer::Impl::close_expired() {
  const auto now = Clock::now();
  std::lock_guard lock(mutex);
  for (auto it = waiting.begin(); it != waiting.end();) {
    if (it->second.deadline > now) {
      ++it;
      continue;
    }
    ::epoll_ctl(epoll_fd, EPOLL_CTL_DEL, it->first, nullptr);
    close_socket(it->first);
    it = waiting.erase(it);
  }
}

void GatedHttpServer::serve(Connection c) {
  Stream stream(c, milliseconds(read_timeout_sec_, read_timeout_usec_),
                milliseconds(write_timeout_sec_, write_timeout_usec_));
  ++c.requests;
  const bool last = c.requests >= keep_alive_max_count_;
  bool closed = false;
  bool ok = false;
  try {
    ok = process_request(stream, last, closed, {});
  } catch (const std::exception&) {
    ok = false;  // httplib answers handler exceptions itself; this is a broken stream
  }
  stream.keep_unread();
  if (ok && !closed && !last) {
    c.deadline = Clock::now() + impl_->limits.header_timeout;
    impl_->admit(std::move(c));  // the next request on this connection waits in the gate
  } else {
    close_socket(c.fd);
  }
}

}  // namespace server
