#include "serve/server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>

#include "base/errors.h"
#include "inspect/html_page.h"
#include "serve/token.h"

namespace fetchscope::serve {
namespace {

void SendError(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(nlohmann::json{{"error", message}}.dump() + "\n", "application/json");
}

void SendJson(httplib::Response& res, const nlohmann::json& body) {
  res.set_content(body.dump() + "\n", "application/json");
}

// A handler that answers every failure with its status and one line of JSON.
template <class F>
httplib::Server::Handler Api(F handle) {
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

}  // namespace

std::string ServePage(const Engine& engine) {
  return HtmlPage(PageKind::kServe, "fetchscope serve", engine.PageData());
}

Server::Server(Engine& engine, ServerOptions options)
    : engine_(engine),
      options_(std::move(options)),
      http_(std::make_unique<httplib::Server>()),
      page_(ServePage(engine)) {
  const size_t max_connections = static_cast<size_t>(std::max(1, options_.max_connections));
  http_->new_task_queue = [max_connections] { return new ConnectionThreads(max_connections); };
  http_->set_payload_max_length(4096);     // every parameter travels in the query
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
  http_->set_default_headers({{"Cache-Control", "no-store"},
                              {"X-Content-Type-Options", "nosniff"},
                              {"Referrer-Policy", "no-referrer"},
                              {"X-Frame-Options", "DENY"}});
  Routes();
}

Server::~Server() = default;

std::string Server::CookieName() const {
  return "fetchscope_token_" + std::to_string(options_.port);
}

void Server::Routes() {
  // the token, before anything else: the first URL's ?token=, the cookie, or a bearer header
  http_->set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    std::string given = req.get_param_value("token");
    if (given.empty()) given = CookieValue(req, CookieName());
    const std::string auth = req.get_header_value("Authorization");
    if (given.empty() && auth.rfind("Bearer ", 0) == 0) given = auth.substr(7);
    if (SameToken(given, options_.token)) {
      // a POST with no Content-Length (curl -X POST) has no body (RFC 9112, 6.3): answered here,
      // where cpp-httplib would wait its read timeout for one and then refuse it
      const auto post = posts_.find(req.path);
      if (req.method == "POST" && post != posts_.end() && !req.has_header("Content-Length") &&
          !req.has_header("Transfer-Encoding")) {
        post->second(req, res);
        return httplib::Server::HandlerResponse::Handled;
      }
      return httplib::Server::HandlerResponse::Unhandled;
    }
    SendError(res, 403,
              given.empty() ? "no token: open the URL fetchscope serve printed (it carries "
                              "?token=...), or send \"Authorization: Bearer TOKEN\""
                            : "wrong token: open the URL fetchscope serve printed");
    return httplib::Server::HandlerResponse::Handled;
  });
  http_->set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    SendError(res, res.status,
              res.status == 404 ? "no such page: " + req.path.substr(0, 80) +
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

  http_->Get("/", [this](const httplib::Request& req, httplib::Response& res) {
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
  http_->Get("/api/page", Api([this](const httplib::Request&, httplib::Response& res) {
               SendJson(res, engine_.PageData());
             }));
  Post("/api/session", Api([this](const httplib::Request&, httplib::Response& res) {
         SendJson(res, {{"session", engine_.NewSession()}});
       }));
  http_->Get("/api/episode", Api([this](const httplib::Request& req, httplib::Response& res) {
               const std::string session = SessionParam(req.params);
               SendJson(res, engine_.Episode(session, ParseEpisodeRequest(req.params)));
             }));
  http_->Get("/api/frame", Api([this](const httplib::Request& req, httplib::Response& res) {
               const std::string session = SessionParam(req.params);
               const Frame frame = engine_.RenderFrame(session, ParseViewRequest(req.params));
               char timing[96];
               std::snprintf(timing, sizeof(timing), "render;dur=%.2f, encode;dur=%.2f",
                             frame.render_ms, frame.encode_ms);
               res.set_header("Server-Timing", timing);
               res.set_header("X-Fetchscope-Camera", frame.camera);
               res.set_content(frame.bytes, frame.content_type);
             }));
  http_->Get("/api/pick", Api([this](const httplib::Request& req, httplib::Response& res) {
               const std::string session = SessionParam(req.params);
               SendJson(res, engine_.Pick(session, ParsePickRequest(req.params)));
             }));
  Post("/api/live/start", Api([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         SendJson(res, engine_.StartLive(session, ParseStartRequest(req.params)));
       }));
  Post("/api/live/step", Api([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         SendJson(res, engine_.StepLive(session, ParseStepRequest(req.params)));
       }));
  Post("/api/live/back", Api([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         ParseStepRequest({});  // no parameters of its own
         SendJson(res, engine_.BackLive(session));
       }));
  Post("/api/live/save", Api([this](const httplib::Request& req, httplib::Response& res) {
         const std::string session = SessionParam(req.params);
         // the view the page shows goes into the record command (camera, overlays, size)
         httplib::Params view = req.params;
         for (const char* name : {"session", "source", "episode", "t"}) view.erase(name);
         view.emplace("source", "live");
         SendJson(res, engine_.SaveLive(session, ParseViewRequest(view)));
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
  options_.port = port;
  return port;
}

void Server::Post(const std::string& path, Handler handler) {
  posts_[path] = handler;
  http_->Post(path, std::move(handler));
}

bool Server::Run() { return http_->listen_after_bind(); }

void Server::Stop() { http_->stop(); }

}  // namespace fetchscope::serve
