// What serve's HTTP side asks of the engine: the page's data, sessions, frames, picks, episodes
// and the live episode. serve::Engine answers them for real (on its GL thread); the router's
// fuzzer (fuzz/fuzz_serve_router.cc) answers them without GL, so that every byte a client can
// send reaches the router, its checks and its error handler there.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "serve/request.h"

namespace fetchscope::serve {

/// One encoded frame.
struct Frame {
  std::string bytes;         ///< the image file
  std::string content_type;  ///< "image/jpeg" or "image/png"
  std::string camera;        ///< the camera shown, as a --camera value
  std::string look;          ///< the look drawn (render/look.h's LookJson, compact); "" plain
  double render_ms = 0;      ///< restoring the state and rendering (GL, readback, HUD)
  double encode_ms = 0;      ///< JPEG or PNG encoding
};

/// The requests of serve's API, typed (serve/request.h). Each throws RequestError (a 4xx or 503)
/// for what it refuses.
class Api {
 public:
  virtual ~Api() = default;
  virtual nlohmann::json PageData() const = 0;
  virtual std::string NewSession() = 0;
  /// Frees a session and its live episode (and exec: child) at once: the page is closing.
  virtual nlohmann::json CloseSession(const std::string& session) = 0;
  virtual Frame RenderFrame(const std::string& session, const ViewRequest& request) = 0;
  virtual nlohmann::json Pick(const std::string& session, const PickRequest& request) = 0;
  virtual nlohmann::json Episode(const std::string& session, const StepRef& episode) = 0;
  /// The episode browser's columns of every episode of a source (serve/sources.h's
  /// EpisodeColumns): {"source", "episodes": [{"index", ...}]}.
  virtual nlohmann::json Listing(const std::string& session, int source) = 0;
  virtual nlohmann::json StartLive(const std::string& session, const StartRequest& request) = 0;
  /// The live episode whole, as StartLive answers (a page that lost its copy asks again).
  virtual nlohmann::json LiveState(const std::string& session) = 0;
  virtual nlohmann::json StepLive(const std::string& session, const StepRequest& request) = 0;
  virtual nlohmann::json BackLive(const std::string& session) = 0;
  virtual nlohmann::json SaveLive(const std::string& session, const ViewRequest& view) = 0;
};

}  // namespace fetchscope::serve
