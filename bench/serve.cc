// bench --what serve: serve's frame budget, measured on its own engine and HTTP server on
// 127.0.0.1 with a 50-step scripted FetchPickAndPlace episode served from a trajectory file and a
// live env: render + encode per frame (JPEG while dragging, PNG at rest), frames a page gets with
// one request in flight, the same with several pages at once, a live key step (the step and its
// frame), the first view of an episode (its replay) and a seek within it. The browser's side
// (frames reaching the page while dragging in Chromium, opening a 1,000-episode run) is
// tools/bench-serve.sh.
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <thread>
#include <vector>

#include "base/atomic_file.h"
#include "bench/bench.h"
#include "render/gl_context.h"
#include "serve/engine.h"
#include "serve/server.h"
#include "serve/token.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/trajectory.h"

namespace fetchscope::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// {"n", "p50", "p95", "mean"} of `values` (ms)
nlohmann::json Summary(std::vector<double> values) {
  if (values.empty()) return {{"n", 0}};
  std::sort(values.begin(), values.end());
  const auto at = [&](double q) {
    return values[std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5))];
  };
  double sum = 0;
  for (double v : values) sum += v;
  return {{"n", values.size()},
          {"p50", at(0.5)},
          {"p95", at(0.95)},
          {"mean", sum / static_cast<double>(values.size())}};
}

// An orbiting camera: frame i of a drag around the default camera's lookat.
std::string Orbit(int i) {
  char text[128];
  std::snprintf(text, sizeof(text),
                "free:lookat=1.3,0.75,0.55,distance=2.5,azimuth=%.2f,elevation=%.2f",
                132.0 + 1.5 * i, -14.0 - 10.0 * std::sin(i * 0.05));
  return text;
}

// A client of `port` with `token`.
std::unique_ptr<httplib::Client> Client(int port, const std::string& token) {
  auto c = std::make_unique<httplib::Client>("127.0.0.1", port);
  c->set_read_timeout(60);
  c->set_keep_alive(true);
  c->set_default_headers({{"Authorization", "Bearer " + token}});
  return c;
}

std::string Session(httplib::Client& c) {
  const auto r = c.Post("/api/session", "", "text/plain");
  return r && r->status == 200 ? nlohmann::json::parse(r->body).value("session", "") : "";
}

// One page dragging: GET frames of an orbiting camera, one in flight, until `until`. Frames.
long Drag(httplib::Client& c, const std::string& session, int width, int height,
          Clock::time_point until, std::vector<double>* round_trips) {
  long frames = 0;
  for (int i = 0; Clock::now() < until; ++i) {
    const auto t0 = Clock::now();
    const auto r =
        c.Get("/api/frame?session=" + session + "&source=0&episode=0&t=25&width=" +
              std::to_string(width) + "&height=" + std::to_string(height) +
              "&format=jpeg&quality=80&camera=" + httplib::detail::encode_query_param(Orbit(i)));
    if (!r || r->status != 200) break;
    if (round_trips) round_trips->push_back(Ms(Clock::now() - t0));
    ++frames;
  }
  return frames;
}

// The served episode: 50 scripted steps of `spec`, written as a trajectory file in `dir`.
std::string WriteServedEpisode(const EnvSpec& spec, const AssetSource& assets,
                               const fs::path& dir) {
  const std::string file = (dir / "episode.json").string();
  FetchEnv env(spec, assets);
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Scripted(), spec, context);
  Trajectory t;
  t.env_id = spec.id;
  t.policy = "scripted";
  t.assets = assets;
  t.episodes = {RunEpisode(env, *policy, 0, 0, 50)};
  WriteFileAtomically(file, TrajectoryText(t));
  return file;
}

// Render + encode on the server, per format (the engine's own clock), an orbiting camera, for
// `seconds` (at least 20 frames) each: out["frame_jpeg"], out["frame_png"] and their bytes.
void FrameBudget(serve::Engine& engine, const std::string& session, int width, int height,
                 double seconds, nlohmann::json* out) {
  for (const char* format : {"jpeg", "png"}) {
    std::vector<double> render, encode, total;
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    for (int i = 0; Clock::now() < until || i < 20; ++i) {
      serve::ViewRequest v;
      v.at = {0, 0, 25};
      v.camera = Orbit(i);
      v.width = width;
      v.height = height;
      v.format =
          std::string(format) == "png" ? serve::ImageFormat::kPng : serve::ImageFormat::kJpeg;
      const serve::Frame f = engine.RenderFrame(session, v);
      render.push_back(f.render_ms);
      encode.push_back(f.encode_ms);
      total.push_back(f.render_ms + f.encode_ms);
      if (i == 0) (*out)[std::string(format) + "_bytes"] = f.bytes.size();
    }
    (*out)[std::string("frame_") + format] = {{"render_ms", Summary(render)},
                                              {"encode_ms", Summary(encode)},
                                              {"total_ms", Summary(total)}};
  }
}

// `pages` pages dragging at once over HTTP for `budget_s`, each with its own session and one
// request in flight: frames/s per page and in all, and the round trips.
nlohmann::json DragPages(int port, const std::string& token, int pages, int width, int height,
                         double budget_s) {
  std::vector<std::unique_ptr<httplib::Client>> clients;
  std::vector<std::string> sessions;
  for (int p = 0; p < pages; ++p) {
    clients.push_back(Client(port, token));
    sessions.push_back(Session(*clients.back()));
    clients.back()->Get("/api/episode?session=" + sessions.back() + "&source=0&episode=0");
  }
  std::vector<long> frames(pages, 0);
  std::vector<std::vector<double>> trips(pages);
  const auto start = Clock::now();
  const Clock::time_point until =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(budget_s));
  std::vector<std::thread> threads;
  for (int p = 0; p < pages; ++p) {
    threads.emplace_back(
        [&, p] { frames[p] = Drag(*clients[p], sessions[p], width, height, until, &trips[p]); });
  }
  for (std::thread& t : threads) t.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  nlohmann::json row = {{"pages", pages}, {"seconds", seconds}};
  long all = 0;
  std::vector<double> every;
  for (int p = 0; p < pages; ++p) {
    all += frames[p];
    every.insert(every.end(), trips[p].begin(), trips[p].end());
  }
  row["frames_per_s_per_page"] = all / seconds / pages;
  row["frames_per_s_total"] = all / seconds;
  row["round_trip_ms"] = Summary(every);
  return row;
}

// 40 live key steps on the live env (source 1), each the step and then its frame: their times.
nlohmann::json KeySteps(httplib::Client& client, const std::string& session, int width,
                        int height) {
  client.Post("/api/live/start?session=" + session + "&env=1", "", "text/plain");
  std::vector<double> steps;
  for (int i = 0; i < 40; ++i) {
    const auto t0 = Clock::now();
    client.Post("/api/live/step?session=" + session + "&action=" + (i % 2 ? "1,0,0,0" : "-1,0,0,0"),
                "", "text/plain");
    client.Get("/api/frame?session=" + session + "&source=live&t=" + std::to_string(i + 1) +
               "&format=jpeg&width=" + std::to_string(width) + "&height=" + std::to_string(height));
    steps.push_back(Ms(Clock::now() - t0));
  }
  return Summary(steps);
}

}  // namespace

nlohmann::json BenchServe(const AssetSource& assets, const std::string& backend, double budget_s,
                          int width, int height) {
  // the served episode: 50 scripted steps, written as a trajectory file
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope_bench_serve_" + serve::NewToken().substr(0, 8));
  fs::create_directories(dir);
  const std::string file = WriteServedEpisode(spec, assets, dir);
  std::vector<serve::Source> sources = {serve::OpenSource(file, dir),
                                        serve::LiveSource(spec, assets, 0)};
  serve::EngineOptions options;
  options.view.backend = ResolveGlBackend(backend);
  options.view.render.msaa_samples = kMsaaAuto;
  options.policy = PolicySpec::Scripted();
  options.max_sessions = 16;
  options.save_dir = dir / "saved";
  serve::Engine engine(std::move(sources), options);
  serve::ServerOptions server_options;
  server_options.port = 0;
  server_options.token = serve::NewToken();
  serve::Server server(engine, server_options, serve::ServePage(engine));
  const int port = server.Bind();
  std::thread listener([&server] { server.Run(); });
  nlohmann::json out = {{"gl", engine.GlJson()}, {"width", width}, {"height", height}};

  auto client = Client(port, server_options.token);
  const std::string session = Session(*client);
  // the first view of the episode: its replay (50 steps, checked), then frames at other steps
  auto t0 = Clock::now();
  client->Get("/api/episode?session=" + session + "&source=0&episode=0");
  out["episode_first_view_ms"] = Ms(Clock::now() - t0);
  std::vector<double> seeks;
  std::mt19937 random(7);
  for (int i = 0; i < 40; ++i) {
    const int t = static_cast<int>(random() % 51);
    t0 = Clock::now();
    client->Get("/api/frame?session=" + session +
                "&source=0&episode=0&format=jpeg&width=" + std::to_string(width) +
                "&height=" + std::to_string(height) + "&t=" + std::to_string(t));
    seeks.push_back(Ms(Clock::now() - t0));
  }
  out["seek_ms"] = Summary(seeks);

  FrameBudget(engine, session, width, height, budget_s / 3, &out);
  // over HTTP: one page dragging (one request in flight), then several pages at once
  for (int pages : {1, 2, 4}) {
    out["drag"].push_back(
        DragPages(port, server_options.token, pages, width, height, budget_s / 3));
  }
  out["key_step_ms"] = KeySteps(*client, session, width, height);
  server.Stop();
  listener.join();
  std::error_code ec;
  fs::remove_all(dir, ec);
  const auto p50 = [&](const char* key, const char* part) {
    return out[key][part]["p50"].get<double>();
  };
  std::printf(
      "serve %dx%d (%s): render+encode p50 %.1f ms JPEG, %.1f ms PNG; one page %.0f "
      "frames/s (round trip p50 %.1f ms), four pages %.0f frames/s each; key step "
      "p50 %.1f ms; seek p50 %.1f ms; first view of a 50-step episode %.0f ms\n",
      width, height, engine.GlJson()["renderer"].get<std::string>().c_str(),
      p50("frame_jpeg", "total_ms"), p50("frame_png", "total_ms"),
      out["drag"][0]["frames_per_s_per_page"].get<double>(),
      out["drag"][0]["round_trip_ms"]["p50"].get<double>(),
      out["drag"][2]["frames_per_s_per_page"].get<double>(),
      out["key_step_ms"]["p50"].get<double>(), out["seek_ms"]["p50"].get<double>(),
      out["episode_first_view_ms"].get<double>());
  return out;
}

}  // namespace fetchscope::bench
