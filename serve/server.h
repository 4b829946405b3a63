// serve's HTTP side (cpp-httplib): the page, its API, and the access check in front of both.
// Every request must carry the token (the first URL's ?token=, then the cookie it sets, or an
// "Authorization: Bearer" header for scripts), checked in constant time; without it, 403. Every
// refusal is a 4xx with one line of JSON, {"error": "..."}, and the server goes on.
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

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "serve/engine.h"

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
  /// connections served at once, each on its own thread (more wait for one to end): a few slow
  /// or idle clients never hold every thread while the page waits
  int max_connections = 256;
};

class Server {
 public:
  Server(Engine& engine, ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds the port (any free one for port 0) and returns it. Throws UsageError naming the port
  /// and what to do when it is in use, or the host when it cannot be bound.
  int Bind();
  /// Serves until Stop (from another thread). Returns false when the server could not run.
  bool Run();
  /// Stops accepting; Run returns once the requests in progress are answered.
  void Stop();

  /// The name of the cookie the token lives in (per port, so two servers on one host do not
  /// overwrite each other's).
  std::string CookieName() const;

 private:
  void Routes();
  /// Registers `handler` for POST `path`, also for a POST without Content-Length (curl -X POST),
  /// which cpp-httplib would read until its read timeout and then refuse.
  using Handler = std::function<void(const httplib::Request&, httplib::Response&)>;
  void Post(const std::string& path, Handler handler);
  Engine& engine_;
  ServerOptions options_;
  std::unique_ptr<httplib::Server> http_;
  std::string page_;                      // the page's HTML, made once
  std::map<std::string, Handler> posts_;  // Post's handlers by path
};

/// The page's HTML for `engine` (inspect/html_page.h, PageKind::kServe).
std::string ServePage(const Engine& engine);

}  // namespace fetchscope::serve
