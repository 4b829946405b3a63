// serve's gate and router in process (serve/http_gate.h, Server::Answer): what a request's head
// must be, which Host names this server, how a client's bytes are quoted, and the router's
// answers to whole connections' bytes, without a socket or GL (tests/serve_attack_test.cc drives
// the real binary; fuzz/fuzz_serve_router.cc the same router with random bytes).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "serve/api.h"
#include "serve/http_gate.h"
#include "serve/server.h"

namespace fetchscope::serve {
namespace {

TEST(ServeGate, PrintableKeepsTextAndEscapesTheRest) {
  EXPECT_EQ(Printable("camera é"), "camera é");
  EXPECT_EQ(Printable("a\xff"), "a\\xff");
  EXPECT_EQ(Printable("a\nb\x7f"), "a\\x0ab\\x7f");
  EXPECT_EQ(Printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");  // a surrogate is not text
  EXPECT_EQ(Printable("\xc3"), "\\xc3");                    // a character cut short
  // cut on a character's boundary: the two bytes of é do not fit in 2
  EXPECT_EQ(Printable("aé", 2), "a...");
  EXPECT_EQ(Printable(std::string(100, 'x'), 80), std::string(80, 'x') + "...");
  EXPECT_TRUE(nlohmann::json::accept(nlohmann::json(Printable("\xff\xfe\x01")).dump()));
}

TEST(ServeGate, OnlyIpLiteralsAndThisServersNamesAreItsHost) {
  const HostRules rules{{"localhost", "node7"}};
  for (const char* host : {"127.0.0.1:8765", "127.0.0.1", "[::1]:8765", "[::1]", "localhost:9000",
                           "LocalHost:1", "node7:8765", "10.1.2.3:80"}) {
    EXPECT_TRUE(HostAllowed(host, rules)) << host;
  }
  for (const char* host : {"evil.example:8765", "evil.example", "localhost.evil.example:1",
                           "127.0.0.1.nip.io:8765", "[::1", "[zz]:1", ":8765", "",
                           "localhost:", "localhost:12a", "localhost:123456", "node7x:1"}) {
    EXPECT_FALSE(HostAllowed(host, rules)) << host;
  }
}

TEST(ServeGate, EachRuleRefusesWithItsStatus) {
  const HostRules rules{{"localhost"}};
  const std::string ok = "GET /api/page?a=1&b=2 HTTP/1.1\r\nHost: 127.0.0.1:1\r\n";
  EXPECT_FALSE(ScreenHead(ok + "\r\n", rules));
  EXPECT_FALSE(ScreenHead(ok + "Content-Length: 0\r\n\r\n", rules));
  std::string flood = ok;
  for (size_t i = 0; i < kMaxHeaderLines; ++i) flood += "X: 1\r\n";
  struct Row {
    std::string head;
    int status;
    const char* says;
  };
  const std::vector<Row> rows = {
      {flood + "\r\n", 431, "header lines"},
      {ok + "Content-Length: 1\r\n\r\n", 413, "takes no body"},
      {ok + "Transfer-Encoding: chunked\r\n\r\n", 413, "Transfer-Encoding"},
      {ok + "Content-Length: 0\r\nContent-Length: 0\r\n\r\n", 400, "2 Content-Length"},
      {ok + "Content-Length: 0\r\nTransfer-Encoding: chunked\r\n\r\n", 400, "both"},
      {ok + "Content-Length: -1\r\n\r\n", 400, "not a number"},
      {ok + "Content-Length: 99999999999999999999\r\n\r\n", 400, "not a number"},
      {"GET /a%00 HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "control byte '%00'"},
      {"GET /a?x=%0a HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "control byte"},
      {"GET /a%zz HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "malformed percent"},
      {"GET /a% HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "malformed percent"},
      {"GET /a\xff HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "\\xff unencoded"},
      {"GET /?a=b=c HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "second '='"},
      {"GET http://x/ HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "does not start with '/'"},
      {"GET / HTTP/2.0\r\nHost: 127.0.0.1\r\n\r\n", 505, "HTTP/2.0"},
      {"GET / HTTP/1.1 x\r\nHost: 127.0.0.1\r\n\r\n", 400, "request line"},
      {"G@T / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400, "method"},
      {"GET / HTTP/1.1\r\n\r\n", 400, "no Host"},
      {ok + "Host: 127.0.0.1\r\n\r\n", 400, "2 Host"},
      {"GET / HTTP/1.1\r\nHost: evil.example:1\r\n\r\n", 403, "does not name this server"},
      {ok + " folded\r\n\r\n", 400, "white space"},
      {ok + "No colon\r\n\r\n", 400, "NAME: VALUE"},
      {ok + "X-\x01: 1\r\n\r\n", 400, "header name"},
      {ok + "X: a\x01b\r\n\r\n", 400, "control byte"},
      {ok + "X: a\rb\r\n\r\n", 400, "bare CR"},
      {"GET / HTTP/1.1\nHost: 127.0.0.1\r\n\r\n", 400, "CR LF"},
      {std::string(kMaxHeadBytes + 1, 'a'), 431, "bytes"},
      {"GET /" + std::string(kMaxTargetBytes, 'a') + " HTTP/1.1\r\nHost: 1.2.3.4\r\n\r\n", 414,
       "bytes"},
  };
  for (const Row& row : rows) {
    const Refusal r = ScreenHead(row.head, rules);
    EXPECT_EQ(r.status, row.status) << Printable(row.head, 200) << ": " << r.message;
    EXPECT_NE(r.message.find(row.says), std::string::npos) << r.message;
    EXPECT_EQ(r.message.find('\n'), std::string::npos) << r.message;
  }
}

// An engine that has only its page's data; everything else is refused.
class PageOnly : public Api {
 public:
  nlohmann::json PageData() const override { return {{"page", 1}}; }
  std::string NewSession() override { return "s"; }
  Frame RenderFrame(const std::string&, const ViewRequest&) override { throw Busy(); }
  nlohmann::json Pick(const std::string&, const PickRequest&) override { throw Busy(); }
  nlohmann::json Episode(const std::string&, const StepRef&) override { throw Busy(); }
  nlohmann::json CloseSession(const std::string&) override { throw Busy(); }
  nlohmann::json Listing(const std::string&, int) override { throw Busy(); }
  nlohmann::json LiveState(const std::string&) override { throw Busy(); }
  nlohmann::json StartLive(const std::string&, const StartRequest&) override { throw Busy(); }
  nlohmann::json StepLive(const std::string&, const StepRequest&) override { throw Busy(); }
  nlohmann::json BackLive(const std::string&) override { throw Busy(); }
  nlohmann::json SaveLive(const std::string&, const ViewRequest&) override { throw Busy(); }

 private:
  static RequestError Busy() { return RequestError(503, "busy"); }
};

TEST(ServeGate, TheRouterAnswersEachRequestOfAConnection) {
  PageOnly api;
  ServerOptions options;
  options.port = 8765;
  options.token = std::string(32, 'k');
  Server server(api, options, "<title>page</title>");
  const std::string auth =
      "Host: 127.0.0.1:8765\r\nAuthorization: Bearer " + options.token + "\r\n";
  // two pipelined requests: two answers, in order
  const std::string two = server.Answer("GET /api/page HTTP/1.1\r\n" + auth +
                                        "\r\nGET /%ff HTTP/1.1\r\n" + auth + "\r\n");
  ASSERT_EQ(two.rfind("HTTP/1.1 200", 0), 0u) << two;
  const size_t second = two.find("HTTP/1.1 404");
  ASSERT_NE(second, std::string::npos) << two;
  EXPECT_NE(two.find("no such page: /\\\\xff", second), std::string::npos) << two;
  // the engine's refusal, the method's, the token's (which closes the connection)
  EXPECT_EQ(server.Answer("GET /api/frame?session=s&source=live HTTP/1.1\r\n" + auth + "\r\n")
                .substr(0, 12),
            "HTTP/1.1 503");
  const std::string method = server.Answer("GET /api/live/step HTTP/1.1\r\n" + auth + "\r\n");
  EXPECT_EQ(method.substr(0, 12), "HTTP/1.1 405") << method;
  EXPECT_NE(method.find("Allow: POST"), std::string::npos) << method;
  const std::string refused = server.Answer(
      "GET /api/page HTTP/1.1\r\nHost: 127.0.0.1:8765\r\n\r\nGET /api/page HTTP/1.1\r\n" + auth +
      "\r\n");
  EXPECT_EQ(refused.substr(0, 12), "HTTP/1.1 403") << refused;
  EXPECT_EQ(refused.find("HTTP/1.1", 12), std::string::npos) << "answered after a 403: " << refused;
  // a head the gate refuses is answered by the gate, and nothing after it
  const std::string gate = server.Answer("GET /api/page HTTP/1.1\r\n" + auth +
                                         "Content-Length: 5\r\n\r\nhelloGET / HTTP/1.1\r\n\r\n");
  EXPECT_EQ(gate.substr(0, 12), "HTTP/1.1 413") << gate;
  EXPECT_NE(gate.find("Connection: close"), std::string::npos) << gate;
  EXPECT_EQ(gate.find("HTTP/1.1", 12), std::string::npos) << gate;
}

}  // namespace
}  // namespace fetchscope::serve
