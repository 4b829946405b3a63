// fetchscope serve: the run folders, datasets and live envs of its command line, in a browser,
// rendered live on this (headless) node (serve/).
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "base/errors.h"
#include "base/stop_signal.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/look_options.h"
#include "cli/obs_options.h"
#include "cli/resolve.h"
#include "cli/view_options.h"
#include "dataset/minari_format.h"
#include "serve/engine.h"
#include "serve/server.h"
#include "serve/sources.h"
#include "serve/token.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

struct ServeOptions {
  std::vector<std::string> sources;
  EnvOptions env;
  PolicyOptions policy;
  ObsOptions obs;    // --obs-camera...: the images an exec: policy's lines carry
  LookOptions look;  // --randomize, --randomize-config: the looks the page draws
  ViewOptions view;
  std::string minari_root;
  std::string host = "127.0.0.1";
  int port = 8765;
  std::string token_file;
  std::string save_dir = "serve-sessions";
  int max_sessions = 8;
  int max_queued = 16;
  double idle_timeout = 600;
};

std::string HostName() {
  char name[256] = "";
  if (gethostname(name, sizeof(name) - 1) != 0 || !name[0]) return "NODE";
  return name;
}

// What serve prints once it listens: a warning beyond loopback, the sources, the GL, the URL
// with its token and the ssh -L line that reaches it from a laptop.
void PrintHowToOpen(const std::string& host, int port, const std::string& token,
                    const serve::Engine& engine) {
  if (host != "127.0.0.1" && host != "localhost" && host != "::1") {
    std::fprintf(stderr,
                 "fetchscope: warning: --host %s: serving on more than this machine's loopback; "
                 "anyone who reaches port %d and has the token can drive it (the default "
                 "127.0.0.1 with ssh -L is safer)\n",
                 host.c_str(), port);
  }
  // an IPv6 address goes in brackets in a URL (http://[::1]:8765/); every interface (0.0.0.0,
  // ::) is shown as the loopback address, which the ssh -L line forwards to
  std::string shown_host = host == "0.0.0.0" ? "127.0.0.1" : host == "::" ? "::1" : host;
  if (shown_host.find(':') != std::string::npos) shown_host = "[" + shown_host + "]";
  for (const serve::Source& s : engine.sources()) {
    std::printf("serve: %s\n", s.title.c_str());
  }
  std::printf("serve: GL %s (%s)\n", engine.GlJson()["renderer"].get<std::string>().c_str(),
              engine.GlJson()["backend"].get<std::string>().c_str());
  std::printf("serve: open http://%s:%d/?token=%s\n", shown_host.c_str(), port, token.c_str());
  std::printf("serve: from a laptop: ssh -N -L %d:127.0.0.1:%d %s, then open that URL there\n",
              port, port, HostName().c_str());
  std::printf("serve: Ctrl-C stops it\n");
  std::fflush(stdout);
}

int RunServe(const ServeOptions& o, const CLI::App& sub) {
  InstallStopSignals();
  const PolicySpec policy = ParsePolicyOptions(o.policy);
  std::vector<serve::Source> sources;
  for (const std::string& given : o.sources) {
    sources.push_back(serve::OpenSource(given, MinariRoot(o.minari_root)));
  }
  // a live env: --env-id given, or nothing else to serve
  if (sub.count("--env-id") > 0 || sources.empty()) {
    const ResolvedEnv env = ResolveEnv(o.env);
    sources.push_back(serve::LiveSource(*env.spec, env.assets, env.seed));
  }
  serve::EngineOptions engine_options;
  engine_options.look = ResolveLook(o.look);
  engine_options.look_seed = ResolveLookSeed(o.look);
  {
    // the view options checked against the first source's model (its cameras), as are the
    // exec: policy's cameras
    FetchEnv first(*sources.front().spec, sources.front().assets);
    engine_options.view = ResolveView(o.view, first.model());
    engine_options.policy_images =
        ResolveObs(o.obs, first.model(), engine_options.view.render.msaa_samples);
  }
  engine_options.camera_text = o.view.camera;
  engine_options.overlay_text = o.view.overlay;
  engine_options.policy = policy;
  for (const serve::Source& s : sources) {  // each env's observation has the fields asked for
    engine_options.policy = WithExecFields(engine_options.policy, o.policy, *s.spec);
  }
  engine_options.save_dir = o.save_dir;
  engine_options.assets_flag = sub.count("--assets") > 0 ? o.env.assets : "";
  engine_options.max_sessions = o.max_sessions;
  engine_options.max_queued = o.max_queued;
  engine_options.idle_timeout_s = o.idle_timeout;

  const std::string token =
      o.token_file.empty() ? serve::NewToken() : serve::TokenFromFile(o.token_file);
  serve::Engine engine(std::move(sources), engine_options);
  serve::ServerOptions server_options;
  server_options.host = o.host;
  server_options.port = o.port;
  server_options.token = token;
  serve::Server server(engine, server_options, serve::ServePage(engine));
  const int port = server.Bind();
  PrintHowToOpen(o.host, port, token, engine);

  std::thread listener([&server] { server.Run(); });
  // wait for SIGINT/SIGTERM, freeing idle sessions now and then
  pollfd stop{StopSignalFd(), POLLIN, 0};
  auto last_sweep = std::chrono::steady_clock::now();
  while (StopSignal() == 0) {
    poll(&stop, 1, 1000);
    if (std::chrono::steady_clock::now() - last_sweep > std::chrono::seconds(10)) {
      try {
        engine.ExpireIdleSessions();
      } catch (const std::exception&) {
        // busy: next time
      }
      last_sweep = std::chrono::steady_clock::now();
    }
  }
  // the queue first (what waits is refused at once, the frame being drawn ends), then every
  // connection: serve exits within a second whatever its clients do
  engine.Stop();
  server.Stop();
  listener.join();
  const int sig = StopSignal();
  std::fprintf(stderr, "fetchscope: serve stopped (%s)\n", sig == SIGINT ? "SIGINT" : "SIGTERM");
  return 128 + sig;
}

}  // namespace

Command AddServe(CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  CLI::App* sub = app.add_subcommand(
      "serve",
      "Serve run folders, trajectory files, Minari datasets and live envs to a browser, rendered "
      "live on this node: any step of any episode (replayed exactly) from any camera, with every "
      "overlay and layer; a live env driven from the keyboard or stepped by --policy, saved as a "
      "replay with the record command that re-renders it. Listens on 127.0.0.1 with a token; use "
      "it from a laptop through ssh -L (docs/guide/serve.md)");
  sub->add_option("SOURCES", o->sources,
                  "Run folders of record, trajectory JSON files, or Minari datasets (an id under "
                  "--minari-root, a dataset folder, or its main_data.hdf5). None: a live env");
  AddEnvOptions(sub, &o->env);
  AddPolicyOptions(sub, &o->policy);
  AddObsOptions(sub, &o->obs);
  AddLookOptions(sub, &o->look,
                 "; a recording's episodes keep their stored looks, and the page's look control "
                 "redraws any step plainly, as recorded, or under another draw");
  o->view.width = 640;  // the page's first view; it can change it
  AddViewOptions(sub, &o->view);
  sub->add_option("--minari-root", o->minari_root,
                  "Where dataset ids are looked up (default $MINARI_DATASETS_PATH, else "
                  "~/.minari/datasets)");
  sub->add_option("--host", o->host,
                  "Address to listen on: 127.0.0.1 (this machine only; reach it with ssh -L) or "
                  "0.0.0.0 (every interface: a warning is printed)")
      ->capture_default_str();
  sub->add_option("--port", o->port, "Port to listen on, 0..65535; 0 picks a free one (printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  sub->add_option("--token-file", o->token_file,
                  "Read the access token from this file (at least 32 characters), or, where it "
                  "does not exist, write a new random one there (mode 0600) for scripts");
  sub->add_option("--save-dir", o->save_dir,
                  "Where the page's Save writes live episodes (session_NNN.json, .csv)")
      ->capture_default_str();
  sub->add_option("--max-sessions", o->max_sessions, "Pages with a session at once, 1..64")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  sub->add_option("--max-queued", o->max_queued,
                  "Requests that may wait for the renderer at once, 1..256 (more are answered "
                  "503)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  sub->add_option("--idle-timeout", o->idle_timeout,
                  "Seconds after which an unused session (and its exec: policy child) is freed")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 86400.0));
  return {sub, [o, sub] {
            CheckObsUse(sub, o->obs, false, o->policy.policy.rfind("exec:", 0) == 0, {});
            return RunServe(*o, *sub);
          }};
}

}  // namespace fetchscope::cli
