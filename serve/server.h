// serve's HTTP side (cpp-httplib): the page, its API, and the checks in front of both.
//
// Every connection is read by serve's own loop (Server::Connection), one request after another:
// a request's whole head must arrive within kHeadDeadlineSeconds and pass the gate
// (serve/http_gate.h: no body, no ambiguous length, text only, a Host that names this server)
// before the library parses it; then the token (the first URL's ?token=, then the cookie it sets,
// or an "Authorization: Bearer" header for scripts), checked in constant time: without it, 403
// and the connection closes. Each path has one method (405 otherwise), and a POST authenticated by
// the cookie must come from serve's own page (its Origin, Content-Type: application/json), so no
// other site's page can drive it. Every refusal is a 4xx with one line of JSON, {"error": "..."}
// (the client's bytes in it escaped), and the server goes on. Stop ends every connection at once.
//
// The API (every parameter is checked by serve/request.h; episodes are named by index):
//   GET  /                      the page (with ?token=: sets the cookie and redirects to /)
//   GET  /api/page              what the page shows first (Engine::PageData)
//   POST /api/session           a new session for the page: {"session": id}
//   GET  /api/episode           a served episode's data           (session, source, episode)
//   GET  /api/frame             a frame of a view at a step: JPEG or PNG (session, the view)
//   GET  /api/pick              what is at a pixel of that view    (session, the view, x, y)
//   POST /api/live/start        a live episode from a live env's reset or a served step
//   POST /api/live/step         one step: an action, or the command line's policy
//   POST /api/live/back         one step back
//   POST /api/live/save         the live episode as a replay trajectory, with its record command
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>

#include "serve/api.h"
#include "serve/http_gate.h"

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace fetchscope::serve {

/// Where and how the server listens.
struct ServerOptions {
  std::string host = "127.0.0.1";  ///< --host
  int port = 8765;                 ///< --port; 0: any free port
  std::string token;               ///< the access token (serve/token.h)
  /// connections served at once, each on its own thread (more wait for one to end): clients that
  /// drip their heads hold one each for at most kHeadDeadlineSeconds, so hundreds of them never
  /// hold every thread while the page waits
  int max_connections = 512;
};

class Gate;  // the HTTP library's server, with serve's connection loop (server.cc)

class Server {
 public:
  /// Serves `api` (the engine) and `page_html` (ServePage) at `options`.
  Server(Api& api, ServerOptions options, std::string page_html);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds the port (any free one for port 0) and returns it. Throws UsageError naming the port
  /// and what to do when it is in use, or the host when it cannot be bound.
  int Bind();
  /// Serves until Stop (from another thread). Returns false when the server could not run.
  bool Run();
  /// Stops accepting and ends every connection (a request being answered is answered if it
  /// can be); Run returns once their threads are done. Stop the engine first (Engine::Stop), so
  /// that no request waits for frames queued behind others.
  void Stop();

  /// The bytes this server answers to `request`, the bytes a client sent on one connection (one
  /// or more requests), read as a connection's are (for the tests and the router's fuzzer).
  std::string Answer(std::string_view request);

  /// The name of the cookie the token lives in (per port, so two servers on one host do not
  /// overwrite each other's).
  std::string CookieName() const;

 private:
  /// The checks and handlers around every route: Admit first, the error and exception handlers.
  void Checks();
  /// The page and the API.
  void Routes();
  using Handler = std::function<void(const httplib::Request&, httplib::Response&)>;
  /// Registers `handler` for GET (and HEAD) `path`.
  void Get(const std::string& path, Handler handler);
  /// Registers `handler` for POST `path`, also for a POST without Content-Length (curl -X POST),
  /// which cpp-httplib would read until its read timeout and then refuse.
  void Post(const std::string& path, Handler handler);
  /// The checks after the gate, before any handler: the token, the method, the origin of a POST.
  bool Admit(const httplib::Request& req, httplib::Response& res);
  Api& api_;
  ServerOptions options_;
  HostRules hosts_;
  std::unique_ptr<Gate> http_;
  std::string page_;                          // the page's HTML, made once
  std::map<std::string, Handler> posts_;      // Post's handlers by path
  std::map<std::string, std::string> paths_;  // each path's method
  friend class Gate;
};

/// The page's HTML for `engine` (inspect/html_page.h, PageKind::kServe).
std::string ServePage(const Api& api);

}  // namespace fetchscope::serve
