// A client of a fetchscope serve that the black-box tests started (testing::ServeProcess): its
// requests with the token as a bearer header (or none), and the check every refusal must pass.
#pragma once

#include <gtest/gtest.h>
#include <httplib.h>

#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/test_util.h"

namespace fetchscope::serve_client {

using nlohmann::json;
using testing::ServeProcess;

// A client of one server, with its token as a bearer header (or none).
struct Api {
  explicit Api(const ServeProcess& serve, bool with_token = true)
      : client("127.0.0.1", serve.port) {
    client.set_read_timeout(120);
    if (with_token) client.set_default_headers({{"Authorization", "Bearer " + serve.token}});
  }
  httplib::Result Get(const std::string& path) { return client.Get(path); }
  httplib::Result Post(const std::string& path) { return client.Post(path, "", "text/plain"); }
  // the JSON of a 200 answer (fails the test otherwise)
  json Json(const httplib::Result& r) {
    EXPECT_TRUE(r) << "no answer";
    if (!r) return json();
    EXPECT_EQ(r->status, 200) << r->body;
    return json::parse(r->body, nullptr, false);
  }
  std::string NewSession() { return Json(Post("/api/session")).value("session", ""); }
  httplib::Client client;
};

// `text` percent-encoded as a query value
inline std::string Encode(const std::string& text) {
  static const char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

// Every refusal: its status and one line of JSON naming what was wrong.
inline void ExpectRefusal(const httplib::Result& r, int status, const std::string& says,
                          const std::string& what) {
  ASSERT_TRUE(r) << what << ": no answer";
  EXPECT_EQ(r->status, status) << what << ": " << r->body;
  EXPECT_EQ(testing::LineCount(r->body), 1) << what << ": " << r->body;
  const json body = json::parse(r->body, nullptr, false);
  ASSERT_TRUE(body.is_object() && body.contains("error")) << what << ": " << r->body;
  EXPECT_NE(body["error"].get<std::string>().find(says), std::string::npos)
      << what << ": " << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/json") << what;
}

// A scripted FetchPickAndPlace run of `steps` steps and `episodes` episodes in dir/run.
inline std::filesystem::path RecordRun(const std::filesystem::path& dir, int episodes, int steps) {
  const auto r = testing::RunFetchscope(
      "record --env-id FetchPickAndPlace-v4 --policy scripted --seed 2 "
      "--episodes " +
      std::to_string(episodes) + " --steps " + std::to_string(steps) +
      " --width 96 --height 72 --quiet --out '" + (dir / "run").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return dir / "run";
}

}  // namespace fetchscope::serve_client
