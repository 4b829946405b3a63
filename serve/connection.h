// serve's connections as the HTTP library reads them (httplib::Stream): the bytes serve's own
// loop has read first (a request's head, screened by serve/http_gate.h before the library parses
// it, and whatever a pipelining client sent after it), then the transport's: a TCP socket whose
// reads and writes wait at most their timeouts, or, for Server::Answer (tests and the router's
// fuzzer), bytes in memory.
#pragma once

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <string>
#include <string_view>

#include "serve/http_gate.h"

namespace fetchscope::serve {

using Clock = std::chrono::steady_clock;

inline int MillisecondsLeft(Clock::time_point until) {
  const auto left =
      std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
  return static_cast<int>(std::clamp<long long>(left, 0, 1 << 30));
}

// A connection as the HTTP library reads it: first the bytes serve's loop has already read (the
// head it screened, and whatever a pipelining client sent after it), then the transport's.
class Connection : public httplib::Stream {
 public:
  enum class Head { kReady, kClosed, kIdle, kLate, kTooLarge };

  // Reads until the buffer holds a whole head (through CR LF CR LF). kIdle: no byte came by
  // `first_byte` (a keep-alive connection the client no longer uses); kLate: a head begun but
  // not finished by `deadline`; kTooLarge: kMaxHeadBytes without its end; kClosed: the client
  // closed the connection (or the server is stopping) first.
  Head ReadHead(Clock::time_point first_byte, Clock::time_point deadline) {
    while (true) {
      const size_t end = buffer_.find("\r\n\r\n", consumed_);
      if (end != std::string::npos) {
        head_end_ = end + 4;
        return Head::kReady;
      }
      if (buffer_.size() - consumed_ > kMaxHeadBytes) return Head::kTooLarge;
      const bool begun = buffer_.size() > consumed_;
      const Clock::time_point until = begun ? deadline : std::min(first_byte, deadline);
      const int wait_ms = MillisecondsLeft(until);
      if (wait_ms == 0) return begun ? Head::kLate : Head::kIdle;
      char chunk[4096];
      const ssize_t n = Receive(chunk, sizeof(chunk), wait_ms);
      if (n == 0) return Head::kClosed;
      if (n > 0) {
        if (consumed_ > 0) {  // what the library has read is dropped before the buffer grows
          buffer_.erase(0, consumed_);
          consumed_ = 0;
        }
        buffer_.append(chunk, static_cast<size_t>(n));
      }
    }
  }
  // The head ReadHead found.
  std::string_view head() const {
    return std::string_view(buffer_).substr(consumed_, head_end_ - consumed_);
  }

  // httplib::Stream: reads come from the buffer first
  bool is_readable() const override { return buffer_.size() > consumed_ || Readable(); }
  ssize_t read(char* ptr, size_t size) override {
    if (buffer_.size() > consumed_) {
      const size_t n = std::min(size, buffer_.size() - consumed_);
      std::memcpy(ptr, buffer_.data() + consumed_, n);
      consumed_ += n;
      return static_cast<ssize_t>(n);
    }
    return Receive(ptr, size, read_timeout_ms_);
  }

 protected:
  // Up to `size` bytes from the transport within `timeout_ms`: the count, 0 at its end, -1 when
  // none came in time.
  virtual ssize_t Receive(char* ptr, size_t size, int timeout_ms) = 0;
  virtual bool Readable() const = 0;
  int read_timeout_ms_ = 5000;

 private:
  std::string buffer_;
  size_t consumed_ = 0;  // what the library has read of buffer_
  size_t head_end_ = 0;
};

// A TCP connection: reads and writes wait at most their timeouts (a client that neither sends nor
// reads is dropped); a write never raises SIGPIPE.
class SocketConnection : public Connection {
 public:
  SocketConnection(socket_t fd, int read_timeout_ms, int write_timeout_ms)
      : fd_(fd), write_timeout_ms_(write_timeout_ms) {
    read_timeout_ms_ = read_timeout_ms;
  }
  bool is_writable() const override { return Wait(POLLOUT, write_timeout_ms_); }
  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    return send(fd_, ptr, size, MSG_NOSIGNAL);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    Address(getpeername, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    Address(getsockname, ip, port);
  }
  socket_t socket() const override { return fd_; }

 protected:
  ssize_t Receive(char* ptr, size_t size, int timeout_ms) override {
    if (!Wait(POLLIN, timeout_ms)) return -1;
    const ssize_t n = recv(fd_, ptr, size, 0);
    return n < 0 ? -1 : n;
  }
  bool Readable() const override { return Wait(POLLIN, read_timeout_ms_); }

 private:
  bool Wait(short events, int timeout_ms) const {
    pollfd p{fd_, events, 0};
    int r;
    do {
      r = poll(&p, 1, timeout_ms);
    } while (r < 0 && errno == EINTR);
    return r > 0;  // POLLHUP/POLLERR too: the read or write then says what happened
  }
  template <class F>
  void Address(F get, std::string& ip, int& port) const {
    sockaddr_storage addr{};
    socklen_t len = sizeof(addr);
    ip.clear();
    port = 0;
    if (get(fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return;
    char text[INET6_ADDRSTRLEN] = "";
    if (addr.ss_family == AF_INET) {
      const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
      inet_ntop(AF_INET, &a->sin_addr, text, sizeof(text));
      port = ntohs(a->sin_port);
    } else if (addr.ss_family == AF_INET6) {
      const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
      inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof(text));
      port = ntohs(a->sin6_port);
    }
    ip = text;
  }
  socket_t fd_;
  int write_timeout_ms_;
};

// The bytes of Server::Answer as a connection: read in one go, the answer collected.
class MemoryConnection : public Connection {
 public:
  explicit MemoryConnection(std::string_view input) : input_(input) {}
  bool is_writable() const override { return true; }
  ssize_t write(const char* ptr, size_t size) override {
    output_.append(ptr, size);
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 40000;
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 8765;
  }
  socket_t socket() const override { return INVALID_SOCKET; }
  const std::string& output() const { return output_; }

 protected:
  ssize_t Receive(char* ptr, size_t size, int) override {
    const size_t n = std::min(size, input_.size());
    std::memcpy(ptr, input_.data(), n);
    input_.remove_prefix(n);
    return static_cast<ssize_t>(n);
  }
  bool Readable() const override { return !input_.empty(); }

 private:
  std::string_view input_;
  std::string output_;
};

}  // namespace fetchscope::serve
