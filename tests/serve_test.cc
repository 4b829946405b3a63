// serve/ in process: the typed requests (every parameter checked at the edge: known names, given
// once, values in range, one line naming what is wrong) and the access token (random, compared in
// constant time, read from or written to a --token-file).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "base/errors.h"
#include "serve/request.h"
#include "serve/token.h"
#include "tests/test_util.h"

namespace fetchscope::serve {
namespace {

Query Q(std::initializer_list<std::pair<std::string, std::string>> pairs) {
  Query q;
  for (const auto& p : pairs) q.emplace(p.first, p.second);
  return q;
}

TEST(ServeRequest, AViewTakesItsDefaultsAndItsParameters) {
  const ViewRequest d = ParseViewRequest(Q({{"session", "s"}, {"source", "2"}, {"episode", "7"}}));
  EXPECT_EQ(d.at.source, 2);
  EXPECT_EQ(d.at.episode, 7);
  EXPECT_EQ(d.at.step, 0);
  EXPECT_EQ(d.camera, "default");
  EXPECT_EQ(d.width, 640);
  EXPECT_EQ(d.height, 480);
  EXPECT_EQ(d.layer, Layer::kRgb);
  EXPECT_EQ(d.format, ImageFormat::kJpeg);
  EXPECT_TRUE(d.overlays.hud);
  const ViewRequest v = ParseViewRequest(Q({{"source", "live"},
                                            {"t", "12"},
                                            {"camera", "track:body=object0,distance=1"},
                                            {"width", "320"},
                                            {"height", "240"},
                                            {"overlay", "goal,trail"},
                                            {"layer", "segmentation"},
                                            {"format", "png"},
                                            {"quality", "95"}}));
  EXPECT_EQ(v.at.source, kLiveSource);
  EXPECT_EQ(v.at.step, 12);
  EXPECT_EQ(v.camera, "track:body=object0,distance=1");
  EXPECT_EQ(v.overlay_text, "goal,trail");
  EXPECT_TRUE(v.overlays.trail);
  EXPECT_FALSE(v.overlays.hud);
  EXPECT_EQ(v.layer, Layer::kSegmentation);
  EXPECT_EQ(v.format, ImageFormat::kPng);
  EXPECT_EQ(v.quality, 95);
}

struct BadCase {
  Query query;
  int status;
  std::string says;
};

TEST(ServeRequest, BadParametersAreRefusedWithTheirStatusAndOneLine) {
  const std::vector<BadCase> cases = {
      {Q({{"source", "0"}}), 400, "parameter 'episode' is missing"},
      {Q({{"source", "0"}, {"episode", "0"}, {"path", "/etc/passwd"}}), 400,
       "unknown parameter 'path'; accepted: camera, episode, format"},
      {Q({{"source", "0"}, {"episode", "0"}, {"episode", "1"}}), 400, "given twice"},
      {Q({{"source", "0x1"}, {"episode", "0"}}), 400, "parameter source '0x1' is not a whole"},
      {Q({{"source", ""}, {"episode", "0"}}), 400, "parameter source '' is not a whole number"},
      {Q({{"source", "1.5"}, {"episode", "0"}}), 400, "not a whole number"},
      {Q({{"source", "0"}, {"episode", "-3"}}), 400, "parameter episode -3 is out of range"},
      {Q({{"source", "0"}, {"episode", "1234567890"}}), 400, "is not a whole number"},
      {Q({{"source", "0"}, {"episode", "0"}, {"t", "100001"}}), 400, "accepted: 0..100000"},
      {Q({{"source", "0"}, {"episode", "0"}, {"width", "0"}}), 400, "accepted: 1..8192"},
      {Q({{"source", "0"}, {"episode", "0"}, {"width", "5000"}, {"height", "5000"}}), 413,
       "frame 5000x5000 is too large"},
      {Q({{"source", "0"}, {"episode", "0"}, {"camera", ""}}), 400, "parameter camera is empty"},
      {Q({{"source", "0"}, {"episode", "0"}, {"camera", std::string(513, 'c')}}), 413,
       "513 bytes long; accepted: at most 512"},
      {Q({{"source", "0"}, {"episode", "0"}, {"overlay", "goal,hug"}}), 400, "did you mean 'hud'"},
      {Q({{"source", "0"}, {"episode", "0"}, {"layer", "RGB"}}), 400, "accepted: rgb, depth, "},
      {Q({{"source", "0"}, {"episode", "0"}, {"format", "webp"}}), 400, "accepted: jpeg, png"},
      {Q({{"source", "0"}, {"episode", "0"}, {"quality", "101"}}), 400, "accepted: 1..100"},
      {Q({{"source", "0"}, {"episode", "0"}, {"x\n", "1"}}), 400, "unknown parameter 'x?'"},
  };
  for (const BadCase& c : cases) {
    try {
      ParseViewRequest(c.query);
      ADD_FAILURE() << c.says << ": accepted";
    } catch (const RequestError& e) {
      EXPECT_EQ(e.status(), c.status) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
}

TEST(ServeRequest, PicksStepsAndStartsAreCheckedToo) {
  const PickRequest pick =
      ParsePickRequest(Q({{"source", "live"}, {"width", "100"}, {"x", "99"}, {"y", "0"}}));
  EXPECT_EQ(pick.x, 99);
  EXPECT_THROW(
      ParsePickRequest(Q({{"source", "live"}, {"width", "100"}, {"x", "100"}, {"y", "0"}})),
      RequestError);
  EXPECT_THROW(ParsePickRequest(Q({{"source", "live"}, {"x", "1"}})), RequestError);  // no y
  EXPECT_FALSE(ParseStepRequest(Q({{"session", "s"}})).action);  // the policy acts
  const StepRequest step = ParseStepRequest(Q({{"action", "0.5,-1,1e-3,-0"}}));
  ASSERT_TRUE(step.action);
  EXPECT_EQ((*step.action)[0], 0.5);
  EXPECT_EQ((*step.action)[2], 0.001);
  for (const std::string bad : {"1,2,3", "1,0,0,0,0", "inf,0,0,0", "0,0,0,", ",0,0,0", "a,b,c,d",
                                "1.0001,0,0,0", "0 ,0,0,0"}) {
    EXPECT_THROW(ParseStepRequest(Q({{"action", bad}})), RequestError) << bad;
  }
  EXPECT_THROW(ParseStepRequest(Q({{"policy", "exec:sh"}})), RequestError);  // never from a page
  EXPECT_EQ(*ParseStartRequest(Q({{"env", "3"}})).env, 3);
  const StartRequest from = ParseStartRequest(Q({{"source", "1"}, {"episode", "4"}, {"t", "9"}}));
  EXPECT_FALSE(from.env);
  EXPECT_EQ(from.from.step, 9);
  EXPECT_THROW(ParseStartRequest(Q({{"env", "0"}, {"t", "2"}})), RequestError);
  EXPECT_THROW(ParseStartRequest(Q({{"source", "live"}})), RequestError);
  EXPECT_THROW(SessionParam(Q({})), RequestError);
}

TEST(ServeToken, TokensAreLongRandomAndComparedWhole) {
  std::set<std::string> seen;
  for (int i = 0; i < 100; ++i) {
    const std::string t = NewToken();
    EXPECT_EQ(t.size(), static_cast<size_t>(kTokenBits / 4));
    EXPECT_EQ(t.find_first_not_of("0123456789abcdef"), std::string::npos) << t;
    EXPECT_TRUE(seen.insert(t).second);
  }
  const std::string t = NewToken();
  EXPECT_TRUE(SameToken(t, t));
  EXPECT_FALSE(SameToken(t.substr(0, 47), t));
  EXPECT_FALSE(SameToken(t + "0", t));
  EXPECT_FALSE(SameToken("", ""));
  std::string flipped = t;
  flipped.back() = flipped.back() == '0' ? '1' : '0';
  EXPECT_FALSE(SameToken(flipped, t));
}

TEST(ServeToken, ATokenFileIsReadOrWrittenForTheUserAlone) {
  testing::TempDir dir;
  const std::string path = (dir.path() / "sub" / "token").string();
  const std::string made = TokenFromFile(path);
  EXPECT_EQ(made.size(), 48u);
  EXPECT_EQ(testing::ReadFile(path), made + "\n");
  struct stat st;
  ASSERT_EQ(stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(TokenFromFile(path), made);  // read back, not replaced
  const std::string mine = (dir.path() / "mine").string();
  std::ofstream(mine) << "my-own.token_with~enough.characters-1234\r\n";
  EXPECT_EQ(TokenFromFile(mine), "my-own.token_with~enough.characters-1234");
  std::ofstream(mine) << "short\n";
  EXPECT_THROW(TokenFromFile(mine), UsageError);
  std::ofstream(mine) << "0123456789abcdef0123456789abcdef has a space\n";
  EXPECT_THROW(TokenFromFile(mine), UsageError);
}

}  // namespace
}  // namespace fetchscope::serve
