// FetchEnv against the reference's semantics: setup, seeded resets, step, observation, reward.
#include "src/fetch_env.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "base/errors.h"
#include "src/episode.h"
#include "src/policy.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

AssetSource Genuine() {
  const auto dir = testing::GenuineAssetsDir();
  return dir.empty() ? AssetSource{} : ResolveAssets(dir.string());
}

#define REQUIRE_GENUINE()                                                   \
  if (testing::GenuineAssetsDir().empty()) {                                \
    GTEST_SKIP() << "genuine Gymnasium-Robotics assets absent (../shared)"; \
  }

void ExpectVec(const std::array<double, 3>& got, std::array<double, 3> want, double tol) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], tol) << "component " << i;
}

// Reference 9.3: settled grip site and object height with the genuine assets on MuJoCo 2.2.2.
TEST(FetchEnvGenuine, SettledStartMatchesReference) {
  REQUIRE_GENUINE();
  const AssetSource g = Genuine();
  FetchEnv reach(FindEnvSpec("FetchReach-v4"), g);
  ExpectVec(reach.initial_gripper_xpos(), {1.341855022, 0.7491005081, 0.5347069462}, 1e-8);
  FetchEnv push(FindEnvSpec("FetchPush-v4"), g);
  ExpectVec(push.initial_gripper_xpos(), {1.348205767, 0.7489488419, 0.4136182913}, 1e-8);
  EXPECT_NEAR(push.height_offset(), 0.4246997495, 1e-9);
  FetchEnv slide(FindEnvSpec("FetchSlide-v4"), g);
  ExpectVec(slide.initial_gripper_xpos(), {0.9961198291, 0.7489058673, 0.4126661756}, 1e-8);
  EXPECT_NEAR(slide.height_offset(), 0.4140189435, 1e-9);
  EXPECT_NEAR(reach.data()->time, 0.4, 1e-12);  // 200 x 0.002
}

// Reference 9.3 goals: the seeded draws (SeedSequence + PCG64 + uniform) in Gymnasium's order.
TEST(FetchEnvGenuine, SeededGoalsMatchReference) {
  REQUIRE_GENUINE();
  const AssetSource g = Genuine();
  FetchEnv reach(FindEnvSpec("FetchReach-v4"), g);
  ExpectVec(reach.Reset(0).desired_goal, {1.382943528, 0.6800365222, 0.3969990034}, 1e-9);
  ExpectVec(reach.Reset(42).desired_goal, {1.424041836, 0.73076404, 0.6422863222}, 1e-8);
  FetchEnv push(FindEnvSpec("FetchPush-v4"), g);
  const Observation p = push.Reset(0);
  ExpectVec(p.desired_goal, {1.442186839, 0.8727755151, 0.4246997495}, 1e-9);
  EXPECT_NEAR(p.observation[3], 1.210497825, 1e-8);  // object x after two placement attempts
  EXPECT_NEAR(p.observation[4], 0.6039071326, 1e-8);
  FetchEnv pick(FindEnvSpec("FetchPickAndPlace-v4"), g);
  ExpectVec(pick.Reset(1).desired_goal, {1.235202906, 0.88369533, 0.7971659167},
            1e-8);  // coin < 0.5: in the air
  FetchEnv slide(FindEnvSpec("FetchSlide-v4"), g);
  ExpectVec(slide.Reset(0).desired_goal, {1.584081973, 0.9965592137, 0.4140189435}, 1e-8);
}

class EveryTask : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryTask, ObservationLayoutAndGoals) {
  FetchEnv env(FindEnvSpec(GetParam()), ResolveAssets("bundled"));
  const Observation obs = env.Reset(3);
  const bool object = env.spec().has_object;
  ASSERT_EQ(obs.observation.size(), object ? 25u : 10u);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(obs.observation[i], env.data()->site_xpos[3 * env.grip_site() + i]);
  if (object) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(obs.achieved_goal[i], obs.observation[3 + i]);
      EXPECT_DOUBLE_EQ(obs.observation[6 + i], obs.observation[3 + i] - obs.observation[i]);
    }
    // object tasks: goal on the table (or lifted, PickAndPlace) at the settled object height
    if (!env.spec().target_in_the_air) {
      EXPECT_EQ(obs.desired_goal[2], env.height_offset());
    }
    // the object starts at least 0.1 m from the gripper in xy
    EXPECT_GE(std::hypot(obs.observation[3] - env.initial_gripper_xpos()[0],
                         obs.observation[4] - env.initial_gripper_xpos()[1]),
              0.1);
  } else {
    for (int i = 0; i < 3; ++i) EXPECT_EQ(obs.achieved_goal[i], obs.observation[i]);
  }
}

TEST_P(EveryTask, SameSeedSameEpisodeAndUnseededResetContinues) {
  FetchEnv a(FindEnvSpec(GetParam()), ResolveAssets("bundled"));
  FetchEnv b(FindEnvSpec(GetParam()), ResolveAssets("bundled"));
  const Observation a0 = a.Reset(7), b0 = b.Reset(7);
  EXPECT_EQ(a0.observation, b0.observation);
  EXPECT_EQ(a0.desired_goal, b0.desired_goal);
  Action act;
  act.value = {0.3, -0.2, 0.1, 0.5};
  for (int t = 0; t < 5; ++t) EXPECT_EQ(a.Step(act).obs.observation, b.Step(act).obs.observation);
  const Observation a1 = a.Reset();
  EXPECT_NE(a1.desired_goal, a0.desired_goal);        // the generator went on
  EXPECT_EQ(a.Reset(7).observation, a0.observation);  // reseeding restores everything
}

TEST_P(EveryTask, TruncatesAtFiftySteps) {
  FetchEnv env(FindEnvSpec(GetParam()), ResolveAssets("bundled"));
  env.Reset(0);
  for (int t = 1; t <= 50; ++t) EXPECT_EQ(env.Step(Action{}).truncated, t == 50) << t;
}

// What a frame, the contact overlay and the next step read from mjData: the derived positions,
// the contacts and the constraint forces, and the state.
std::vector<double> DerivedValues(const FetchEnv& env) {
  const mjModel* m = env.model();
  const mjData* d = env.data();
  std::vector<double> v;
  const auto add = [&v](const mjtNum* p, int n) { v.insert(v.end(), p, p + n); };
  add(&d->time, 1);
  add(d->qpos, m->nq);
  add(d->qvel, m->nv);
  add(d->qacc_warmstart, m->nv);
  add(d->xpos, 3 * m->nbody);
  add(d->xquat, 4 * m->nbody);
  add(d->geom_xpos, 3 * m->ngeom);
  add(d->geom_xmat, 9 * m->ngeom);
  add(d->site_xpos, 3 * m->nsite);
  add(d->subtree_com, 3 * m->nbody);
  add(d->mocap_pos, 3 * m->nmocap);
  v.push_back(d->ncon);
  for (int i = 0; i < d->ncon; ++i) {
    add(d->contact[i].pos, 3);
    add(d->contact[i].frame, 9);
    v.push_back(d->contact[i].dist);
    v.push_back(d->contact[i].geom1);
    v.push_back(d->contact[i].geom2);
  }
  v.push_back(d->nefc);
  add(d->efc_force, d->nefc);
  return v;
}

// A checkpoint taken after the reset or any step, restored on the same env later or on another
// env, gives every derived value bit for bit (contacts and forces of a grasp included), and
// stepping on from it gives the episode of an env that never stopped.
TEST_P(EveryTask, RestoredCheckpointsGiveTheSameDataAndTheSameEpisode) {
  const EnvSpec& spec = FindEnvSpec(GetParam());
  FetchEnv env(spec, ResolveAssets("bundled"));
  env.EnableCheckpoints();
  EXPECT_THROW(env.Checkpoint(), RunError);  // none before a reset
  PolicyContext context;
  context.seed = 4;
  auto policy = MakePolicy(PolicySpec::Scripted(), spec, context);
  std::vector<EnvCheckpoint> checkpoints;
  std::vector<std::vector<double>> derived;
  std::vector<Action> actions{Action{}};
  int most_contacts = 0;
  const EpisodeRecord episode =
      RunEpisode(env, *policy, 0, 4, 30, [&](const StepRecord& r, const StepResult*) {
        checkpoints.push_back(env.Checkpoint());
        derived.push_back(DerivedValues(env));
        if (r.action) actions.push_back(*r.action);
        most_contacts = std::max(most_contacts, env.data()->ncon);
        return true;
      });
  ASSERT_EQ(checkpoints.size(), 31u);
  EXPECT_GT(most_contacts, 0);
  FetchEnv other(spec, ResolveAssets("bundled"));
  for (int k : {0, 1, 12, 29}) {
    for (FetchEnv* target : {&env, &other}) {
      target->Restore(checkpoints[k]);
      ASSERT_EQ(DerivedValues(*target), derived[k]) << "step " << k;
      EXPECT_EQ(target->elapsed_steps(), k);
      EXPECT_EQ(target->goal(), episode.steps[k].obs.desired_goal);
      for (int t = k + 1; t <= 30; ++t) {
        const StepResult r = target->Step(actions[t]);
        ASSERT_EQ(r.obs.observation, episode.steps[t].obs.observation) << k << " -> " << t;
        ASSERT_EQ(DerivedValues(*target), derived[t]) << k << " -> " << t;
      }
    }
  }
  // the generator comes back too: the next reset after a restore is the next reset of the run
  FetchEnv straight(spec, ResolveAssets("bundled"));
  straight.Reset(4);
  const Observation next = straight.Reset();
  other.Restore(checkpoints[5]);
  EXPECT_EQ(other.Reset().desired_goal, next.desired_goal);
}

INSTANTIATE_TEST_SUITE_P(Fetch, EveryTask,
                         ::testing::Values("FetchReach-v4", "FetchPush-v4", "FetchPickAndPlace-v4",
                                           "FetchSlide-v4"));

TEST(FetchEnv, SparseRewardUsesStrictGreaterAndSuccessStrictLess) {
  FetchEnv sparse(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  FetchEnv dense(FindEnvSpec("FetchReachDense-v4"), ResolveAssets("bundled"));
  const std::array<double, 3> a{0, 0, 0}, at{0.05, 0, 0}, beyond{0.0500001, 0, 0},
      inside{0.03, 0.03, 0};
  EXPECT_EQ(sparse.ComputeReward(a, at), 0.0);
  EXPECT_TRUE(std::signbit(sparse.ComputeReward(a, at)));  // -0.0, as numpy gives
  EXPECT_FALSE(sparse.IsSuccess(a, at));                   // d == threshold: no success
  EXPECT_EQ(sparse.ComputeReward(a, beyond), -1.0);
  EXPECT_TRUE(sparse.IsSuccess(a, inside));
  EXPECT_DOUBLE_EQ(dense.ComputeReward(a, {0.03, 0.04, 0}), -0.05);
}

TEST(FetchEnv, Float32ActionsAreScaledInFloat32) {
  FetchEnv env(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  env.Reset(0);
  const mjData* d = env.data();
  const int body = env.gripper_body();
  // a component whose float32 product differs from the double one
  float x = 0.3f;
  while (static_cast<double>(x * 0.05f) == static_cast<double>(x) * 0.05)
    x = std::nextafter(x, 1.0f);
  for (bool f32 : {true, false}) {
    const double anchor = d->xpos[3 * body];
    Action act;
    act.is_float32 = f32;
    act.value = {static_cast<double>(x), 0, 0, 0};
    env.Step(act);
    const double expected = f32 ? static_cast<double>(x * 0.05f) : static_cast<double>(x) * 0.05;
    EXPECT_EQ(d->mocap_pos[0] - anchor, (anchor + expected) - anchor)
        << (f32 ? "float32" : "float64");
  }
}

TEST(FetchEnv, ClipsActionsToUnitBox) {
  FetchEnv env(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  env.Reset(0);
  Action big;
  big.value = {5, -7, 0.5, 3};
  const StepResult r = env.Step(big);
  EXPECT_EQ(r.applied[0], 1.0);
  EXPECT_EQ(r.applied[1], -1.0);
  EXPECT_EQ(r.applied[2], 0.5);
}

TEST(FetchEnv, BlockedGripperFingersStayClosedAndPickAndPlaceOpensOnPositive) {
  FetchEnv reach(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  reach.Reset(0);
  Action open;
  open.value = {0, 0, 0, 1};
  for (int t = 0; t < 5; ++t) {
    const StepResult r = reach.Step(open);
    EXPECT_EQ(r.obs.observation[3], 0.0);
    EXPECT_EQ(r.obs.observation[4], 0.0);
  }
  FetchEnv pick(FindEnvSpec("FetchPickAndPlace-v4"), ResolveAssets("bundled"));
  const double start = pick.Reset(0).observation[9];
  double opened = 0;
  for (int t = 0; t < 5; ++t) opened = pick.Step(open).obs.observation[9];
  EXPECT_GT(opened, start + 0.01);  // action[3] > 0 opens (reference section 11, item 9)
  Action close;
  close.value = {0, 0, 0, -1};
  double closed = opened;
  for (int t = 0; t < 5; ++t) closed = pick.Step(close).obs.observation[9];
  EXPECT_LT(closed, opened - 0.01);
}

// PickAndPlace has no step callback, so its observed kinematics are one substep stale;
// Reach runs mj_forward after the substeps (reference section 11, item 1).
TEST(FetchEnv, PickAndPlaceObservationIsOneSubstepStale) {
  for (const char* id : {"FetchReach-v4", "FetchPickAndPlace-v4"}) {
    FetchEnv env(FindEnvSpec(id), ResolveAssets("bundled"));
    env.Reset(0);
    Action move;
    move.value = {1, 0, 0, 0};
    const StepResult r = env.Step(move);
    MjDataPtr fresh(mj_makeData(env.model()));
    mj_copyData(fresh.get(), env.model(), env.data());
    mj_forward(env.model(), fresh.get());
    const double diff = std::abs(fresh->site_xpos[3 * env.grip_site()] - r.obs.observation[0]);
    if (std::string(id) == "FetchReach-v4") {
      EXPECT_LT(diff, 1e-12) << id;
    } else {
      EXPECT_GT(diff, 1e-6) << id;
    }
  }
}

TEST(FetchEnv, VelocitiesArePerStepDisplacements) {
  FetchEnv env(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  env.Reset(0);
  Action move;
  move.value = {0, 0, 1, 0};
  for (int t = 0; t < 4; ++t) env.Step(move);
  const Observation before = env.Observe();
  const Observation after = env.Step(move).obs;
  // grip_velp (index 5..7) is velocity * dt: close to the displacement over that step
  EXPECT_NEAR(after.observation[7], after.observation[2] - before.observation[2], 0.01);
  EXPECT_GT(after.observation[7], 0.005);
}

TEST(FetchEnv, UnknownIdListsValidIds) {
  try {
    FindEnvSpec("FetchReach-v3");
    FAIL() << "no exception";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("FetchPickAndPlaceDense-v4"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("FetchReach-v3"), std::string::npos);
  }
  EXPECT_EQ(FindEnvSpec("auto").id, "FetchReachDense-v4");
}

TEST(FetchEnv, Mat2EulerMatchesGymnasiumConventions) {
  const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const auto e = Mat2Euler(identity);
  EXPECT_EQ(e[0], 0.0);
  EXPECT_TRUE(std::signbit(e[0]));  // (-0.0, 0.0, -0.0) as rotations.py gives
  EXPECT_FALSE(std::signbit(e[1]));
  EXPECT_TRUE(std::signbit(e[2]));
  // 90 degrees about z: M = [[0,-1,0],[1,0,0],[0,0,1]] -> ez = -atan2(M01, M00) = pi/2
  const double rz[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
  EXPECT_NEAR(Mat2Euler(rz)[2], M_PI / 2, 1e-15);
}

}  // namespace
}  // namespace fetchscope
