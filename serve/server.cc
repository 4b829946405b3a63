#include "serve/server.h"

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>

#include "base/errors.h"
#include "serve/connection.h"
#include "serve/token.h"

namespace fetchscope::serve {
namespace {

// One line of JSON for a refusal. The message may quote a client's bytes (a path, a parameter):
// Printable escapes whatever is not valid UTF-8 text, so that the JSON can always be written (an
// invalid byte once made dump() throw outside every handler's try, and ended the process).
std::string ErrorBody(const std::string& message) {
  return nlohmann::json{{"error", Printable(message, 4096)}}.dump(
             -1, ' ', false, nlohmann::json::error_handler_t::replace) +
         "\n";
}

void SendError(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(ErrorBody(message), "application/json");
}

void SendJson(httplib::Response& res, const nlohmann::json& body) {
  res.set_content(body.dump() + "\n", "application/json");
}

// A handler that answers every failure with its status and one line of JSON.
template <class F>
httplib::Server::Handler ApiHandler(F handle) {
  return [handle](const httplib::Request& req, httplib::Response& res) {
    try {
      handle(req, res);
    } catch (const RequestError& e) {
      SendError(res, e.status(), e.what());
    } catch (const UsageError& e) {
      SendError(res, 400, e.what());
    } catch (const std::exception& e) {
      SendError(res, 500, e.what());
    }
  };
}

// The value of cookie `name` in the request's Cookie headers, or "".
std::string CookieValue(const httplib::Request& req, const std::string& name) {
  for (size_t i = 0; i < req.get_header_value_count("Cookie"); ++i) {
    const std::string header = req.get_header_value("Cookie", i);
    size_t at = 0;
    while (at < header.size()) {
      size_t end = header.find(';', at);
      if (end == std::string::npos) end = header.size();
      std::string pair = header.substr(at, end - at);
      while (!pair.empty() && pair.front() == ' ') pair.erase(0, 1);
      if (pair.rfind(name + "=", 0) == 0) return pair.substr(name.size() + 1);
      at = end + 1;
    }
  }
  return "";
}

// cpp-httplib's task queue: each connection on a thread of its own, at most `max` at once (more
// wait for one to end). A fixed pool of 16 threads was held by 16 connections that sent their
// headers a byte a second (no token needed for that), and the page waited behind them.
class ConnectionThreads : public httplib::TaskQueue {
 public:
  explicit ConnectionThreads(size_t max) : max_(max) {}

  void enqueue(std::function<void()> fn) override {
    std::unique_lock<std::mutex> lock(mutex_);
    if (running_ >= max_) {
      waiting_.push_back(std::move(fn));
      return;
    }
    ++running_;
    try {
      std::thread([this, fn = std::move(fn)]() mutable { Serve(std::move(fn)); }).detach();
    } catch (const std::system_error&) {  // no thread to be had (the user's process limit)
      if (--running_ > 0) {
        waiting_.push_back(std::move(fn));  // a running thread takes it next
        return;
      }
      lock.unlock();
      fn();  // on the accepting thread: slower, but served
    }
  }

  // httplib calls it once it has stopped accepting, and deletes the queue after it returns
  void shutdown() override {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return running_ == 0; });
  }

 private:
  // A connection's thread: serves it, then whichever waits, then ends.
  void Serve(std::function<void()> fn) {
    for (;;) {
      fn();
      std::lock_guard<std::mutex> lock(mutex_);
      if (waiting_.empty()) {
        if (--running_ == 0) idle_.notify_all();
        return;
      }
      fn = std::move(waiting_.front());
      waiting_.pop_front();
    }
  }

  const size_t max_;
  std::mutex mutex_;
  std::condition_variable idle_;
  size_t running_ = 0;
  std::deque<std::function<void()>> waiting_;
};

// Whether the response being written closes its connection (a refusal of the token or the
// method): set by Server::Admit, read by the connection's loop, on the connection's thread.
thread_local bool close_after_response = false;

// The status line's words for the statuses the gate answers.
const char* Reason(int status) {
  switch (status) {
    case 400:
      return "Bad Request";
    case 403:
      return "Forbidden";
    case 408:
      return "Request Timeout";
    case 413:
      return "Content Too Large";
    case 414:
      return "URI Too Long";
    case 431:
      return "Request Header Fields Too Large";
    case 505:
      return "HTTP Version Not Supported";
    default:
      return "Error";
  }
}

}  // namespace

// cpp-httplib's server with serve's connection loop in place of the library's own (whose read
// timeout was per read, so that a client dripping a byte every 2 s held its thread for ever, and
// which read chunked bodies of any size): each request's head is read whole, within its deadline,
// and screened by the gate; only then does the library parse it and route it.
class Gate : public httplib::Server {
 public:
  Gate(serve::Server& owner) : owner_(owner) {}

  // A bigger listen backlog than the library's 5: a burst of connections (a page's images, many
  // clients) waits in the kernel's queue instead of being refused.
  void Relisten() {
    if (svr_sock_ != INVALID_SOCKET) ::listen(svr_sock_, SOMAXCONN);
  }

  // Stops the loops: the connections' sockets are shut down, so that every wait on them ends now.
  void CloseAll() {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    for (socket_t fd : open_) shutdown(fd, SHUT_RDWR);
  }

  // One connection, request after request, until it closes, idles, fails a check or the server
  // stops. True when it ended on a refusal (its client may still be sending).
  bool Serve(Connection& conn) {
    for (size_t served = 0; !stopping_; ++served) {
      const Clock::time_point start = Clock::now();
      const auto deadline =
          start + std::chrono::milliseconds(static_cast<int>(kHeadDeadlineSeconds * 1000));
      const auto first_byte =
          served == 0 ? deadline : start + std::chrono::seconds(keep_alive_timeout_sec_);
      switch (conn.ReadHead(first_byte, deadline)) {
        case Connection::Head::kReady:
          break;
        case Connection::Head::kLate:
          Refuse(conn, {408, "the request's head did not arrive within " +
                                 std::to_string(static_cast<int>(kHeadDeadlineSeconds)) + " s"});
          return true;
        case Connection::Head::kTooLarge:
          Refuse(conn, {431, "the request's head has more than " + std::to_string(kMaxHeadBytes) +
                                 " bytes"});
          return true;
        default:
          return false;  // closed, or idle
      }
      if (Refusal refusal = ScreenHead(conn.head(), owner_.hosts_)) {
        Refuse(conn, refusal);
        return true;
      }
      close_after_response = false;
      bool closed = false;
      const bool last = stopping_ || served + 1 >= keep_alive_max_count_;
      bool answered = false;
      try {
        answered = process_request(conn, last, closed, nullptr);
      } catch (...) {  // whatever a request throws ends its connection, never the process
        return false;
      }
      if (close_after_response) return true;
      if (!answered || closed || last) return false;
    }
    return false;
  }

 private:
  bool process_and_close_socket(socket_t sock) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) {
        close(sock);
        return false;
      }
      open_.insert(sock);
    }
    bool refused = false;
    {
      SocketConnection conn(sock, static_cast<int>(read_timeout_sec_ * 1000),
                            static_cast<int>(write_timeout_sec_ * 1000));
      refused = Serve(conn);
    }
    if (refused && !stopping_) Linger(sock);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      open_.erase(sock);
    }
    shutdown(sock, SHUT_RDWR);
    close(sock);
    return true;
  }

  // After a refusal the client may still be sending what was refused (a body, a flood of
  // headers): closing with its bytes unread would reset the connection, and the client could lose
  // the answer. So the answer is followed by the end of our side, and what the client still sends
  // is read and dropped, for at most 2 s and 4 MiB (the server's stop ends it at once).
  void Linger(socket_t sock) {
    shutdown(sock, SHUT_WR);
    const Clock::time_point until = Clock::now() + std::chrono::seconds(2);
    size_t dropped = 0;
    char sink[16384];
    while (dropped < (4u << 20) && !stopping_) {
      pollfd p{sock, POLLIN, 0};
      if (poll(&p, 1, std::min(MillisecondsLeft(until), 200)) <= 0) {
        if (MillisecondsLeft(until) == 0) return;
        continue;
      }
      const ssize_t n = recv(sock, sink, sizeof(sink), 0);
      if (n <= 0) return;
      dropped += static_cast<size_t>(n);
    }
  }

  // The gate's answer, written here: the library has not parsed the request.
  void Refuse(Connection& conn, const Refusal& refusal) {
    const std::string body = ErrorBody(refusal.message);
    std::string response =
        "HTTP/1.1 " + std::to_string(refusal.status) + " " + Reason(refusal.status) + "\r\n";
    for (const auto& [name, value] : kDefaultHeaders) response += name + ": " + value + "\r\n";
    response += "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
                "\r\nConnection: close\r\n\r\n" + body;
    size_t at = 0;
    while (at < response.size()) {
      const ssize_t n = conn.write(response.data() + at, response.size() - at);
      if (n <= 0) return;
      at += static_cast<size_t>(n);
    }
  }

  serve::Server& owner_;
  std::mutex mutex_;
  std::set<socket_t> open_;
  std::atomic<bool> stopping_{false};

 public:
  static const httplib::Headers kDefaultHeaders;
};

const httplib::Headers Gate::kDefaultHeaders = {{"Cache-Control", "no-store"},
                                                {"X-Content-Type-Options", "nosniff"},
                                                {"Referrer-Policy", "no-referrer"},
                                                {"X-Frame-Options", "DENY"}};

Server::Server(Api& api, ServerOptions options, std::string page_html)
    : api_(api),
      options_(std::move(options)),
      http_(std::make_unique<Gate>(*this)),
      page_(std::move(page_html)) {
  const size_t max_connections = static_cast<size_t>(std::max(1, options_.max_connections));
  http_->new_task_queue = [max_connections] { return new ConnectionThreads(max_connections); };
  http_->set_payload_max_length(0);        // the gate refuses every body: parameters are queries
  http_->set_keep_alive_timeout(2);        // an idle browser connection gives its thread back
  http_->set_keep_alive_max_count(10000);  // a dragging page keeps its connection (default: 5)
  http_->set_read_timeout(5);
  http_->set_write_timeout(5);  // a client that never reads is dropped
  http_->set_tcp_nodelay(true);
  // SO_REUSEADDR only: cpp-httplib also sets SO_REUSEPORT, with which a second serve of the same
  // user would bind the same port and take half its connections instead of being refused
  http_->set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  http_->set_default_headers(Gate::kDefaultHeaders);
  // the Host names that name this server besides IP literals: a page under any other name (DNS
  // rebinding) is refused by the gate
  hosts_.names = {"localhost"};
  in6_addr literal{};
  if (!options_.host.empty() && inet_pton(AF_INET, options_.host.c_str(), &literal) != 1 &&
      inet_pton(AF_INET6, options_.host.c_str(), &literal) != 1) {
    hosts_.names.push_back(options_.host);
  }
  char node[256] = "";
  if (gethostname(node, sizeof(node) - 1) == 0 && node[0]) {
    hosts_.names.push_back(node);
    const std::string full = node;
    if (full.find('.') != std::string::npos) hosts_.names.push_back(full.substr(0, full.find('.')));
  }
  Checks();
  Routes();
}

Server::~Server() = default;

std::string Server::CookieName() const {
  return "fetchscope_token_" + std::to_string(options_.port);
}

namespace {

// The media type of a Content-Type value, lower case, without its parameters.
std::string MediaType(const std::string& value) {
  std::string type = value.substr(0, value.find(';'));
  while (!type.empty() && (type.back() == ' ' || type.back() == '\t')) type.pop_back();
  while (!type.empty() && (type.front() == ' ' || type.front() == '\t')) type.erase(0, 1);
  for (char& c : type) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return type;
}

}  // namespace

bool Server::Admit(const httplib::Request& req, httplib::Response& res) {
  auto refuse = [&res](int status, const std::string& message) {
    close_after_response = true;  // a refused client gets no kept-alive connection
    res.set_header("Connection", "close");
    SendError(res, status, message);
    return false;
  };
  // the token: the first URL's ?token=, the cookie, or a bearer header
  std::string given = req.get_param_value("token");
  const bool by_cookie = given.empty() && !CookieValue(req, CookieName()).empty();
  if (given.empty()) given = CookieValue(req, CookieName());
  const std::string auth = req.get_header_value("Authorization");
  if (given.empty() && auth.rfind("Bearer ", 0) == 0) given = auth.substr(7);
  if (!SameToken(given, options_.token)) {
    return refuse(403, given.empty() ? "no token: open the URL fetchscope serve printed (it "
                                       "carries ?token=...), or send \"Authorization: Bearer "
                                       "TOKEN\""
                                     : "wrong token: open the URL fetchscope serve printed");
  }
  // each path has its method (HEAD with GET's)
  const bool known_method = req.method == "GET" || req.method == "HEAD" || req.method == "POST";
  const auto path = paths_.find(req.path);
  if (!known_method || (path != paths_.end() && path->second != req.method &&
                        !(path->second == "GET" && req.method == "HEAD"))) {
    const std::string allowed = path == paths_.end()    ? "GET, HEAD, POST"
                                : path->second == "GET" ? "GET, HEAD"
                                                        : "POST";
    res.set_header("Allow", allowed);
    return refuse(405, "method " + Printable(req.method) + " is not accepted on " +
                           (path == paths_.end() ? "this server" : req.path) + ": " + allowed);
  }
  // a POST that the cookie authenticates comes from serve's own page, or from nowhere: another
  // origin's page can make the browser send the cookie (a form, a no-cors fetch), never this
  // Origin with an application/json Content-Type. Scripts send the bearer header instead.
  if (req.method == "POST" && by_cookie) {
    const std::string origin = req.get_header_value("Origin");
    const std::string own = "http://" + req.get_header_value("Host");
    if (origin != own) {
      return refuse(403,
                    "a POST authenticated by the cookie must come from serve's own page "
                    "(Origin " +
                        own + ", not '" + Printable(origin) +
                        "'); scripts send \"Authorization: Bearer TOKEN\"");
    }
    if (MediaType(req.get_header_value("Content-Type")) != "application/json") {
      return refuse(403,
                    "a POST authenticated by the cookie must say Content-Type: "
                    "application/json, as serve's page does (a form on another site "
                    "cannot)");
    }
  }
  return true;
}

void Server::Checks() {
  // after the gate (serve/http_gate.h), before any handler: Admit
  http_->set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (!Admit(req, res)) return httplib::Server::HandlerResponse::Handled;
    // a POST with no Content-Length (curl -X POST) has no body (RFC 9112, 6.3): answered here,
    // where cpp-httplib would wait its read timeout for one and then refuse it
    const auto post = posts_.find(req.path);
    if (req.method == "POST" && post != posts_.end() && !req.has_header("Content-Length")) {
      post->second(req, res);
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  http_->set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    SendError(res, res.status,
              res.status == 404 ? "no such page: " + Printable(req.path, 80) +
                                      " (the API is /api/page, /api/frame, ...)"
                                : "request refused (HTTP " + std::to_string(res.status) + ")");
  });
  http_->set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr e) {
        try {
          std::rethrow_exception(e);
        } catch (const std::exception& x) {
          SendError(res, 500, x.what());
        } catch (...) {
          SendError(res, 500, "internal error");
        }
      });
}

void Server::Routes() {
  Get("/", [this](const httplib::Request& req, httplib::Response& res) {
    if (req.has_param("token")) {  // the first URL: the token becomes a cookie, the URL loses it
      res.set_header("Set-Cookie", CookieName() + "=" + options_.token +
                                       "; Path=/; Max-Age=86400; HttpOnly; SameSite=Strict");
      res.set_redirect("/", 303);
      return;
    }
    res.set_header("Content-Security-Policy",
                   "default-src 'self'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                   "img-src 'self' blob: data:; connect-src 'self'; frame-ancestors 'none'");
    res.set_content(page_, "text/html; charset=utf-8");
  });
  Get("/api/page", ApiHandler([this](const httplib::Request&, httplib::Response& res) {
        SendJson(res, api_.PageData());
      }));
  Post("/api/session", ApiHandler([this](const httplib::Request&, httplib::Response& res) {
         SendJson(res, {{"session", api_.NewSession()}});
       }));
  Post("/api/session/close",
       ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         CheckNoParameters(req.params);
         SendJson(res, api_.CloseSession(session));
       }));
  Get("/api/live", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
        const std::string session = SessionParam(req.params);
        CheckNoParameters(req.params);
        SendJson(res, api_.LiveState(session));
      }));
  Get("/api/listing", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
        const std::string session = SessionParam(req.params);
        SendJson(res, api_.Listing(session, ParseSourceRequest(req.params)));
      }));
  Get("/api/episode", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
        const std::string session = SessionParam(req.params);
        SendJson(res, api_.Episode(session, ParseEpisodeRequest(req.params)));
      }));
  Get("/api/frame", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
        const std::string session = SessionParam(req.params);
        const Frame frame = api_.RenderFrame(session, ParseViewRequest(req.params));
        char timing[96];
        std::snprintf(timing, sizeof(timing), "render;dur=%.2f, encode;dur=%.2f", frame.render_ms,
                      frame.encode_ms);
        res.set_header("Server-Timing", timing);
        res.set_header("X-Fetchscope-Camera", Printable(frame.camera, 4096));
        res.set_header("X-Fetchscope-Look", Printable(frame.look, 8192));
        res.set_content(frame.bytes, frame.content_type);
      }));
  Get("/api/pick", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
        const std::string session = SessionParam(req.params);
        SendJson(res, api_.Pick(session, ParsePickRequest(req.params)));
      }));
  Post("/api/live/start", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         SendJson(res, api_.StartLive(session, ParseStartRequest(req.params)));
       }));
  Post("/api/live/step", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         SendJson(res, api_.StepLive(session, ParseStepRequest(req.params)));
       }));
  Post("/api/live/back", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         CheckNoParameters(req.params);
         SendJson(res, api_.BackLive(session));
       }));
  Post("/api/live/save", ApiHandler([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         // the view the page shows goes into the record command (camera, overlays, size)
         httplib::Params view = req.params;
         for (const char* name : {"session", "source", "episode", "t"}) view.erase(name);
         view.emplace("source", "live");
         SendJson(res, api_.SaveLive(session, ParseViewRequest(view)));
       }));
}

int Server::Bind() {
  int port = options_.port;
  if (port == 0) {
    port = http_->bind_to_any_port(options_.host);
  } else if (!http_->bind_to_port(options_.host, port)) {
    port = -1;
  }
  if (port < 0) {
    if (options_.port != 0) {
      throw UsageError("--port " + std::to_string(options_.port) + " on " + options_.host +
                       " cannot be bound (in use by another program, or not this machine's "
                       "address): choose another --port, or --port 0 for any free one");
    }
    throw UsageError("--host " + options_.host +
                     " cannot be bound: give an address of this "
                     "machine (127.0.0.1, the default, or 0.0.0.0 for every interface)");
  }
  http_->Relisten();
  options_.port = port;
  return port;
}

void Server::Get(const std::string& path, Handler handler) {
  paths_[path] = "GET";
  http_->Get(path, std::move(handler));
}

void Server::Post(const std::string& path, Handler handler) {
  paths_[path] = "POST";
  posts_[path] = handler;
  http_->Post(path, std::move(handler));
}

bool Server::Run() { return http_->listen_after_bind(); }

void Server::Stop() {
  http_->CloseAll();
  http_->stop();
  http_->CloseAll();  // a connection accepted while the listening socket closed
}

std::string Server::Answer(std::string_view request) {
  MemoryConnection conn(request);
  http_->Serve(conn);
  return conn.output();
}

}  // namespace fetchscope::serve
