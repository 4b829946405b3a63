// Contacts (src/contacts.h) and everything that shows them: the signals in the trajectory
// (--signals contacts), the overlay (--overlay contacts), compare's first contact difference and
// probe-actions' grasp report. Forces are mj_contactForce's for the very state, the fingers press
// only in a grasp, and recording them never changes a step.
#include "src/contacts.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "encode/png_io.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

// A scripted PickAndPlace episode with its contacts and each step's checkpoint.
struct Grasp {
  EpisodeRecord episode;
  std::vector<EnvCheckpoint> checkpoints;
};

Grasp ScriptedGrasp(FetchEnv& env, int steps) {
  env.EnableCheckpoints();
  env.EnableContactSignals();
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Scripted(), env.spec(), context);
  Grasp g;
  g.episode = RunEpisode(env, *policy, 0, 0, steps, [&](const StepRecord&, const StepResult*) {
    g.checkpoints.push_back(env.Checkpoint());
    return true;
  });
  return g;
}

TEST(Contacts, ForcesAreMujocosForTheSameStateThroughTheTrajectoryFile) {
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  const Grasp g = ScriptedGrasp(env, 25);
  // the file's values, written and read back
  Trajectory t;
  t.env_id = spec.id;
  t.assets = env.assets();
  t.episodes = {g.episode};
  const Trajectory back = ParseTrajectory(TrajectoryText(t), "grasp.json");
  EXPECT_EQ(back.schema_version, kTrajectorySchemaVersion);  // an addition: the version stays
  FetchEnv other(spec, ResolveAssets("bundled"));
  int compared = 0;
  for (size_t k = 0; k < g.checkpoints.size(); ++k) {
    other.Restore(g.checkpoints[k]);
    const mjData* d = other.data();
    const std::vector<Contact>& read = back.episodes[0].steps[k].contacts->contacts;
    size_t n = 0;
    for (int i = 0; i < d->ncon; ++i) {
      if (d->contact[i].efc_address < 0) continue;
      ASSERT_LT(n, read.size()) << "step " << k;
      mjtNum force[6];
      mj_contactForce(other.model(), d, i, force);
      EXPECT_NEAR(read[n].normal_force, force[0], 1e-9) << "step " << k << " contact " << i;
      EXPECT_NEAR(read[n].penetration, std::max(0.0, -d->contact[i].dist), 1e-12);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(read[n].position[c], d->contact[i].pos[c]);
      ++n;
      ++compared;
    }
    EXPECT_EQ(n, read.size()) << "step " << k;
  }
  EXPECT_GT(compared, 100);
}

TEST(Contacts, FingersPressOnlyInAGraspAndTheObjectLeavesTheTable) {
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  const Grasp g = ScriptedGrasp(env, 25);
  const ContactSignals& reset = *g.episode.steps[0].contacts;
  EXPECT_EQ(reset.left_finger_force, 0.0);  // the gripper open, in the air
  EXPECT_EQ(reset.right_finger_force, 0.0);
  EXPECT_FALSE(reset.grasped());
  EXPECT_TRUE(reset.object_on_table);
  for (const Contact& c : reset.contacts) {
    EXPECT_NE(c.pair, ContactPair::kFingerObject) << c.geom1 << "/" << c.geom2;
    if (c.pair == ContactPair::kObjectTable) {
      EXPECT_GT(c.normal_force, 0);
      EXPECT_EQ(c.body2 == "object0" ? c.body1 : c.body2, "table0");
      EXPECT_GT(c.push[2], 0.9);  // the table pushes the object up
    }
  }
  int grasped = 0, lifted = 0;
  for (const TrajectoryStep& s : g.episode.steps) {
    if (!s.contacts->grasped()) continue;
    ++grasped;
    EXPECT_GT(s.contacts->left_finger_force, 1.0) << "step " << s.t;
    EXPECT_GT(s.contacts->right_finger_force, 1.0) << "step " << s.t;
    lifted += !s.contacts->object_on_table;
  }
  EXPECT_GT(grasped, 5);
  EXPECT_GT(lifted, 3);
  // Reach has no object: no finger-object pair, no object on the table
  FetchEnv reach(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  reach.EnableContactSignals();
  reach.Reset(0);
  EXPECT_FALSE(reach.Contacts()->object_on_table);
  EXPECT_EQ(FindContactBodies(reach.model()).object, -1);
}

TEST(Contacts, TheGenuineAssetsNameTheSamePairs) {
  if (testing::GenuineAssetsDir().empty()) GTEST_SKIP() << "genuine assets absent (../shared)";
  FetchEnv env(FindEnvSpec("FetchPickAndPlace-v4"),
               ResolveAssets(testing::GenuineAssetsDir().string()));
  const ContactBodies b = FindContactBodies(env.model());
  EXPECT_GE(b.left_finger, 0);
  EXPECT_GE(b.right_finger, 0);
  EXPECT_GE(b.object, 0);
  EXPECT_GE(b.table, 0);
  const Grasp g = ScriptedGrasp(env, 20);
  bool grasped = false;
  for (const TrajectoryStep& s : g.episode.steps) grasped = grasped || s.contacts->grasped();
  EXPECT_TRUE(grasped);
}

// --signals contacts adds "contacts" to every step and changes nothing else
TEST(ContactSignals, RecordingThemNeverChangesTheSimulation) {
  for (const char* env : {"FetchPickAndPlace-v4", "FetchPush-v4", "FetchSlide-v4"}) {
    const auto plain = RunFetchscope(std::string("rollout --env-id ") + env +
                                     " --policy scripted --episodes 2 --steps 30 --seed 4");
    const auto with = RunFetchscope(std::string("rollout --env-id ") + env +
                                    " --policy scripted --episodes 2 --steps 30 --seed 4 "
                                    "--signals contacts");
    ASSERT_EQ(plain.exit_code, 0) << plain.output;
    ASSERT_EQ(with.exit_code, 0) << with.output;
    json a = json::parse(plain.output), b = json::parse(with.output);
    for (json& e : b["episodes"]) {
      for (json& s : e["steps"]) {
        ASSERT_TRUE(s.contains("contacts"));
        s.erase("contacts");
      }
    }
    EXPECT_EQ(a, b) << env;
  }
  const auto bad = RunFetchscope("rollout --signals contact");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--signals 'contact' is not known (did you mean 'contacts'?)"),
            std::string::npos)
      << bad.output;
}

// Pixels of the finger-object colour (magenta, lit and shaded: red and blue high, green low).
long MagentaPixels(const Image& image) {
  long n = 0;
  for (size_t i = 0; i + 2 < image.pixels.size(); i += 3) {
    const int r = image.pixels[i], g = image.pixels[i + 1], b = image.pixels[i + 2];
    n += r > 150 && b > 110 && g < 70 && r - g > 100;
  }
  return n;
}

TEST(ContactOverlay, FingerObjectMarksShowInAGraspAndNotAtTheReset) {
  TempDir dir;
  const std::string camera = "free:lookat=1.35,0.75,0.45,distance=0.8,azimuth=150,elevation=-25";
  const auto frame = [&](int steps, const std::string& overlay) {
    const fs::path png = dir.path() / ("f" + std::to_string(steps) + overlay + ".png");
    const auto r = RunFetchscope("render --env-id FetchPickAndPlace-v4 --policy scripted --steps " +
                                 std::to_string(steps) + " --overlay " + overlay + " --camera '" +
                                 camera + "' --width 240 --height 240 -o " + png.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return ReadPng(png.string());
  };
  const Image reset = frame(0, "goal,contacts"), reset_plain = frame(0, "goal");
  const Image grasp = frame(16, "goal,contacts"), grasp_plain = frame(16, "goal");
  EXPECT_EQ(MagentaPixels(reset), 0);
  EXPECT_EQ(MagentaPixels(grasp_plain), 0);
  EXPECT_GT(MagentaPixels(grasp), 200);
  // the object-table marks at the reset: the frame differs from the plain one
  EXPECT_NE(reset.pixels, reset_plain.pixels);
}

TEST(ContactOverlay, JobsGiveTheSameBytesWithContactsOn) {
  TempDir dir;
  std::vector<std::map<std::string, std::string>> runs;
  for (int jobs : {1, 2}) {
    const fs::path out = dir.path() / ("jobs" + std::to_string(jobs));
    const auto r = RunFetchscope(
        "record --env-id FetchPickAndPlace-v4 --policy scripted "
        "--episodes 3 --steps 20 --width 96 --height 96 --signals contacts "
        "--overlay default,contacts --no-report -q --jobs " +
        std::to_string(jobs) + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    runs.push_back(testing::EpisodeFiles(out));
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  EXPECT_EQ(runs[0], runs[1]);
  EXPECT_NE(runs[0].at("episode_000.json").find("\"left_finger_force\""), std::string::npos);
}

TEST(ContactCompare, SaysWhereTheContactSequencesFirstDiffer) {
  TempDir dir;
  const auto record = [&](const std::string& name, const std::string& policy) {
    const auto r = RunFetchscope(
        "record --env-id FetchPickAndPlace-v4 --episodes 1 --steps 20 "
        "--width 64 --height 64 --signals contacts --no-report -q "
        "--policy " +
        policy + " --out " + (dir.path() / name).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  };
  record("scripted", "scripted");
  record("zero", "zero");
  record("again", "scripted");
  const auto differ = RunFetchscope("compare " + (dir.path() / "scripted").string() + " " +
                                    (dir.path() / "zero").string() + " --states-only --out " +
                                    (dir.path() / "cmp").string());
  EXPECT_EQ(differ.exit_code, 1) << differ.output;
  const json rows = json::parse(ReadFile(dir.path() / "cmp" / "compare.json"))["episodes"];
  const json& c = rows[0]["first_contact_difference"];
  ASSERT_TRUE(c.is_object()) << rows[0];
  ASSERT_TRUE(c["step"].is_number()) << c;
  EXPECT_GT(c["step"].get<int>(), 0) << c;  // the resets are the same
  EXPECT_NE(differ.output.find("contacts first differ at step " + c["step"].dump()),
            std::string::npos)
      << differ.output;
  EXPECT_NE(c["only_a"].dump().find("finger-object"), std::string::npos) << c;
  const auto same = RunFetchscope("compare " + (dir.path() / "scripted").string() + " " +
                                  (dir.path() / "again").string() + " --states-only --out " +
                                  (dir.path() / "cmp2").string());
  EXPECT_EQ(same.exit_code, 0) << same.output;
  const json rows2 = json::parse(ReadFile(dir.path() / "cmp2" / "compare.json"))["episodes"];
  EXPECT_TRUE(rows2[0]["first_contact_difference"]["step"].is_null());
}

TEST(GraspProbe, PickAndPlaceClosesOnTheObjectAndLiftsItPushHasNoGrasp) {
  TempDir dir;
  const auto r = RunFetchscope("probe-actions --env-id FetchPickAndPlace-v4 --json-out " +
                               (dir.path() / "pnp.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json g = json::parse(ReadFile(dir.path() / "pnp.json"))["grasp"];
  ASSERT_TRUE(g["done"].get<bool>()) << g;
  EXPECT_EQ(g["after_close"]["fingers_touching"],
            json::array({"robot0:l_gripper_finger_link", "robot0:r_gripper_finger_link"}));
  EXPECT_GT(g["after_close"]["left_finger_force"].get<double>(), 1.0);
  EXPECT_GT(g["after_close"]["right_finger_force"].get<double>(), 1.0);
  EXPECT_TRUE(g["after_close"]["grasped"].get<bool>());
  EXPECT_TRUE(g["lift"]["lifts"].get<bool>()) << g;
  EXPECT_GT(g["lift"]["object_rise"].get<double>(), 0.05);
  EXPECT_NE(r.output.find("grasp: after closing above the object both fingers touch it"),
            std::string::npos)
      << r.output;
  const auto push = RunFetchscope("probe-actions --env-id FetchPush-v4 --json-out " +
                                  (dir.path() / "push.json").string());
  ASSERT_EQ(push.exit_code, 0) << push.output;
  const json p = json::parse(ReadFile(dir.path() / "push.json"))["grasp"];
  EXPECT_FALSE(p["done"].get<bool>());
  EXPECT_NE(p["why"].get<std::string>().find("blocks the gripper"), std::string::npos);
}

}  // namespace
}  // namespace fetchscope
