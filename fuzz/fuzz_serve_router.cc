// libFuzzer target: serve's whole router, from the bytes a client sends on one connection: the
// gate (serve/http_gate.h), the HTTP library's parsing, the token, method and origin checks, every
// route's parameter parsing, the handlers' refusals and the error and exception handlers. The
// engine behind it answers without GL (each answer quotes the request back, as the real one
// quotes names and values in its refusals). Findings: a crash or sanitizer report, a request
// whose head arrived whole and got no answer, and an answer whose JSON body does not parse.
#include <cstdlib>
#include <string>

#include "fuzz/fuzz_common.h"
#include "serve/api.h"
#include "serve/server.h"

namespace {

using fetchscope::serve::RequestError;
using nlohmann::json;

// Answers each request from its parsed parameters; a session "bad" is refused, and one that
// starts with "throw" throws what no handler expects, so the exception handler runs too.
class EchoApi : public fetchscope::serve::Api {
 public:
  json PageData() const override { return {{"page", true}}; }
  std::string NewSession() override { return "s1"; }
  json CloseSession(const std::string& session) override {
    Check(session);
    return {{"closed", true}};
  }
  json LiveState(const std::string& session) override {
    Check(session);
    return {{"steps", 0}};
  }
  fetchscope::serve::Frame RenderFrame(const std::string& session,
                                       const fetchscope::serve::ViewRequest& r) override {
    Check(session);
    fetchscope::serve::Frame frame;
    frame.bytes = "frame";
    frame.content_type = "image/png";
    frame.camera = r.camera;  // quoted back in a header, as the engine does
    return frame;
  }
  json Pick(const std::string& session, const fetchscope::serve::PickRequest& r) override {
    Check(session);
    return {{"x", r.x}, {"camera", r.view.camera}};
  }
  json Episode(const std::string& session, const fetchscope::serve::StepRef& e) override {
    Check(session);
    return {{"source", e.source}, {"episode", e.episode}};
  }
  json Listing(const std::string& session, int source) override {
    Check(session);
    return {{"source", source}};
  }
  json StartLive(const std::string& session, const fetchscope::serve::StartRequest&) override {
    Check(session);
    return {{"steps", 0}};
  }
  json StepLive(const std::string& session, const fetchscope::serve::StepRequest&) override {
    Check(session);
    return {{"steps", 1}};
  }
  json BackLive(const std::string& session) override {
    Check(session);
    return {{"steps", 0}};
  }
  json SaveLive(const std::string& session, const fetchscope::serve::ViewRequest& v) override {
    Check(session);
    return {{"command", "fetchscope record --camera " + v.camera}};
  }

 private:
  static void Check(const std::string& session) {
    if (session.rfind("throw", 0) == 0) throw std::runtime_error("unexpected: " + session);
    if (session != "s1") throw RequestError(404, "no session '" + session + "'");
  }
};

const std::string kToken(32, 't');

fetchscope::serve::Server& TheServer() {
  static EchoApi api;
  static fetchscope::serve::Server* server = [] {
    fetchscope::serve::ServerOptions options;
    options.port = 8765;
    options.token = kToken;
    return new fetchscope::serve::Server(api, options, "<!doctype html><title>page</title>");
  }();
  return *server;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input = fetchscope::fuzz::AsString(data, size);
  const std::string out = TheServer().Answer(input);
  const size_t head_end = input.find("\r\n\r\n");
  if (head_end == std::string::npos) return 0;
  // a request whose head arrived whole is answered (the first request at least)
  if (out.rfind("HTTP/1.1 ", 0) != 0) std::abort();
  const size_t out_head = out.find("\r\n\r\n");
  if (out_head == std::string::npos) std::abort();
  const std::string head = out.substr(0, out_head);
  const size_t length_at = head.find("\r\nContent-Length: ");
  if (length_at == std::string::npos) std::abort();
  // an answer to HEAD has its Content-Length and no body
  if (input.rfind("HEAD ", 0) == 0) return 0;
  const size_t length = std::strtoul(head.c_str() + length_at + 18, nullptr, 10);
  if (out.size() < out_head + 4 + length) std::abort();
  // every JSON answer (the refusals' one line among them) parses
  if (head.find("\r\nContent-Type: application/json") != std::string::npos &&
      !json::accept(out.substr(out_head + 4, length))) {
    std::abort();
  }
  return 0;
}
