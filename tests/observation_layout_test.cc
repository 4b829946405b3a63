// The observation layout (src/observation_layout.h) against the reference (section 5.3) and
// against what FetchEnv::Observe really builds.
#include "src/observation_layout.h"

#include <gtest/gtest.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"

namespace fetchscope {
namespace {

// {slice, first, end} as the reference's table 5.3 gives them
struct Expected {
  const char* name;
  int first, end;
};

void ExpectSlices(bool has_object, const std::vector<Expected>& want) {
  const std::vector<ObservationSlice> got = ObservationSlices(has_object);
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(got[i].name, want[i].name) << i;
    EXPECT_EQ(got[i].first, want[i].first) << want[i].name;
    EXPECT_EQ(got[i].end, want[i].end) << want[i].name;
  }
}

TEST(ObservationLayout, ReachMatchesTheReference) {
  EXPECT_EQ(ObservationSize(false), 10);
  ExpectSlices(
      false,
      {{"grip_pos", 0, 3}, {"gripper_state", 3, 5}, {"grip_velp", 5, 8}, {"gripper_vel", 8, 10}});
  EXPECT_EQ(ObservationIndexName(false, 3), "gripper_state.right");
  EXPECT_EQ(ObservationIndexName(false, 4), "gripper_state.left");
  EXPECT_EQ(ObservationIndexName(false, 9), "gripper_vel.left");
}

TEST(ObservationLayout, ObjectTasksMatchTheReference) {
  EXPECT_EQ(ObservationSize(true), 25);
  ExpectSlices(true, {{"grip_pos", 0, 3},
                      {"object_pos", 3, 6},
                      {"object_rel_pos", 6, 9},
                      {"gripper_state", 9, 11},
                      {"object_rot", 11, 14},
                      {"object_velp", 14, 17},
                      {"object_velr", 17, 20},
                      {"grip_velp", 20, 23},
                      {"gripper_vel", 23, 25}});
  EXPECT_EQ(ObservationIndexName(true, 5), "object_pos.z");
  EXPECT_EQ(ObservationIndexName(true, 11), "object_rot.x");
  EXPECT_EQ(ObservationIndexUnit(true, 11), "rad");
  EXPECT_EQ(ObservationIndexUnit(true, 17), "rad/step");
  EXPECT_EQ(ObservationIndexUnit(true, 14), "m/step");
  EXPECT_EQ(ObservationIndex(true, "object_pos.z"), 5);
  EXPECT_EQ(ObservationIndex(false, "object_pos.z"), -1);
}

TEST(ObservationLayout, EveryIndexIsNamedOnceAndTheSlicesCoverIt) {
  for (const bool has_object : {false, true}) {
    const std::vector<LayoutLabel>& labels = ObservationLabels(has_object);
    ASSERT_EQ(static_cast<int>(labels.size()), ObservationSize(has_object));
    std::set<std::string> names;
    for (const LayoutLabel& l : labels) {
      EXPECT_TRUE(names.insert(l.name).second) << l.name << " named twice";
      EXPECT_NE(std::string(l.name).find('.'), std::string::npos) << l.name;
      EXPECT_GT(std::string(l.meaning).size(), 10u) << l.name;
      const std::set<std::string> units = {"m", "m/step", "rad", "rad/step"};
      EXPECT_TRUE(units.count(l.unit)) << l.name << ": " << l.unit;
    }
    // consecutive, without a gap, and no slice appears twice
    int next = 0;
    std::set<std::string> slices;
    for (const ObservationSlice& s : ObservationSlices(has_object)) {
      EXPECT_EQ(s.first, next) << s.name;
      EXPECT_GT(s.end, s.first) << s.name;
      EXPECT_TRUE(slices.insert(s.name).second) << s.name << " twice";
      for (int i = s.first; i < s.end; ++i) {
        EXPECT_EQ(std::string(labels[i].name).rfind(s.name + ".", 0), 0u) << labels[i].name;
        EXPECT_EQ(ObservationIndex(has_object, labels[i].name), i);
      }
      next = s.end;
    }
    EXPECT_EQ(next, ObservationSize(has_object));
  }
}

TEST(ObservationLayout, FingersAndSlicesAsTheChapterWritesThem) {
  EXPECT_EQ(FingerPositionIndices(false).right, 3);
  EXPECT_EQ(FingerPositionIndices(false).left, 4);
  EXPECT_EQ(FingerPositionIndices(true).right, 9);
  EXPECT_EQ(FingerPositionIndices(true).left, 10);
  EXPECT_EQ(FingerWidthText(false), "obs[3] + obs[4]");
  EXPECT_EQ(FingerWidthText(true), "obs[9] + obs[10]");
  EXPECT_EQ(ObservationSliceText(false, "grip_pos"), "obs[0:3]");
  EXPECT_EQ(ObservationSliceText(true, "object_rel_pos"), "obs[6:9]");
  EXPECT_EQ(ObservationSliceText(false, "object_pos"), "");
  EXPECT_FALSE(FindObservationSlice(false, "object_rot").has_value());
  EXPECT_EQ((ObservationSlice{"one", 3, 4}).Text(), "obs[3]");
}

TEST(ObservationLayout, NamesAFlatIndexForMessages) {
  EXPECT_EQ(ObservationIndexText(true, 11), "observation[11] (object_rot.x, rad)");
  EXPECT_EQ(ObservationIndexText(false, 0), "observation[0] (grip_pos.x, m)");
  EXPECT_EQ(ObservationIndexText(false, 7), "observation[7] (grip_velp.z, m/step)");
  // past the end: the index alone
  EXPECT_EQ(ObservationIndexText(false, 10), "observation[10]");
  EXPECT_EQ(ObservationIndexText(true, 25), "observation[25]");
  EXPECT_EQ(ObservationIndexName(false, 10), "");
  EXPECT_EQ(ObservationIndexUnit(true, 99), "");
}

// what a replay's divergence messages (record --from DATASET) take from the layout
TEST(ObservationLayout, LengthsGoalsAndDisplayUnits) {
  EXPECT_EQ(LayoutHasObject(10), std::optional<bool>(false));
  EXPECT_EQ(LayoutHasObject(25), std::optional<bool>(true));
  EXPECT_EQ(LayoutHasObject(0), std::nullopt);
  EXPECT_EQ(LayoutHasObject(12), std::nullopt);
  EXPECT_EQ(GoalIndexName("desired_goal", 1), "desired_goal.y");
  EXPECT_EQ(GoalIndexName("achieved_goal", 2), "achieved_goal.z");
  EXPECT_STREQ(kGoalUnit, "m");
  // metres as millimetres, other units as they are
  EXPECT_DOUBLE_EQ(InDisplayUnit(0.25, "m").value, 250);
  EXPECT_EQ(InDisplayUnit(0.25, "m").unit, "mm");
  EXPECT_EQ(InDisplayUnit(0.002, "m/step").unit, "mm/step");
  EXPECT_DOUBLE_EQ(InDisplayUnit(0.5, "rad").value, 0.5);
  EXPECT_EQ(InDisplayUnit(0.5, "rad/step").unit, "rad/step");
  EXPECT_EQ(FormatInDisplayUnit(-0.0000139, "m"), "-0.0139 mm");
  EXPECT_EQ(FormatInDisplayUnit(0.0002, "m/step"), "0.2 mm/step");
  EXPECT_EQ(FormatInDisplayUnit(0.0642, "rad"), "0.0642 rad");
  EXPECT_EQ(FormatInDisplayUnit(0.1234, "m"), "123 mm");
  EXPECT_EQ(FormatInDisplayUnit(1.5, ""), "1.5");
}

TEST(ObservationLayout, ActionComponents) {
  for (const bool blocked : {false, true}) {
    const std::vector<LayoutLabel> a = ActionLabels(blocked);
    ASSERT_EQ(a.size(), 4u);
    EXPECT_STREQ(a[0].name, "dx");
    EXPECT_STREQ(a[1].name, "dy");
    EXPECT_STREQ(a[2].name, "dz");
    EXPECT_STREQ(a[kActionGripper].name, "gripper");
    EXPECT_STREQ(a[0].unit, "0.05 m");
  }
  EXPECT_EQ(std::string(ActionLabels(true)[3].meaning).rfind("ignored", 0), 0u);
  EXPECT_NE(std::string(ActionLabels(false)[3].meaning).find("OPENS"), std::string::npos);
}

// What FetchEnv::Observe builds is where the layout says: the goal, the relative position and
// the finger joints (right before left) at their named indices, for every task.
TEST(ObservationLayout, MatchesWhatTheEnvBuilds) {
  for (const char* id :
       {"FetchReach-v4", "FetchPush-v4", "FetchPickAndPlace-v4", "FetchSlide-v4"}) {
    SCOPED_TRACE(id);
    const EnvSpec& spec = FindEnvSpec(id);
    FetchEnv env(spec, ResolveAssets("bundled"));
    env.Reset(3);
    Observation obs;
    for (int t = 0; t < 4; ++t) obs = env.Step(Action{{0.3, -0.2, 0.1, 1.0}, false}).obs;
    const bool object = spec.has_object;
    const std::vector<double>& o = obs.observation;
    ASSERT_EQ(static_cast<int>(o.size()), ObservationSize(object));
    const int goal = FindObservationSlice(object, object ? "object_pos" : "grip_pos")->first;
    for (int i = 0; i < 3; ++i) EXPECT_EQ(o[goal + i], obs.achieved_goal[i]) << i;
    const mjModel* m = env.model();
    const FingerIndices f = FingerPositionIndices(object);
    const int r = mj_name2id(m, mjOBJ_JOINT, "robot0:r_gripper_finger_joint");
    const int l = mj_name2id(m, mjOBJ_JOINT, "robot0:l_gripper_finger_joint");
    ASSERT_GE(r, 0);
    ASSERT_GE(l, 0);
    EXPECT_EQ(o[f.right], env.data()->qpos[m->jnt_qposadr[r]]);
    EXPECT_EQ(o[f.left], env.data()->qpos[m->jnt_qposadr[l]]);
    if (object) {
      const int grip = FindObservationSlice(true, "grip_pos")->first;
      const int rel = FindObservationSlice(true, "object_rel_pos")->first;
      for (int i = 0; i < 3; ++i) EXPECT_EQ(o[rel + i], o[goal + i] - o[grip + i]) << i;
    }
  }
}

}  // namespace
}  // namespace fetchscope
