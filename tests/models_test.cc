// Checks the bundled primitive-geom Fetch models (models/*.xml): they compile cleanly, settle
// sensibly, and, when the genuine Gymnasium-Robotics assets are present, compile to the same
// kinematics, inertias, sites, cameras, constraints and scene items as the genuine models and
// settle to the same gripper position.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "src/mj_handles.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

constexpr double kTol = 1e-9;        // compiled numbers that come straight from the XML
constexpr double kEqDataTol = 1e-6;  // weld relpose, computed from forward kinematics
constexpr double kSettleTol = 3e-3;  // settled grip site, bundled versus genuine

std::string BundledPath(const std::string& task) {
  return std::string(FETCHSCOPE_SOURCE_DIR) + "/models/" + task + ".xml";
}

/// Collects MuJoCo warnings (mju_warning) while alive; restores the previous handler after.
class WarningCapture {
 public:
  WarningCapture() : previous_(mju_user_warning) {
    Messages().clear();
    mju_user_warning = &WarningCapture::Handler;
  }
  ~WarningCapture() { mju_user_warning = previous_; }
  WarningCapture(const WarningCapture&) = delete;
  WarningCapture& operator=(const WarningCapture&) = delete;

  /// Warnings seen so far.
  static std::vector<std::string>& Messages() {
    static std::vector<std::string> messages;
    return messages;
  }

 private:
  static void Handler(const char* msg) { Messages().emplace_back(msg ? msg : ""); }
  void (*previous_)(const char*);
};

/// Compiles an MJCF file; on failure returns null and puts MuJoCo's message in *message.
/// On success *message holds whatever MuJoCo left in its error buffer (warnings).
MjModelPtr LoadModel(const std::string& path, std::string* message) {
  char error[1024] = "";
  MjModelPtr model(mj_loadXML(path.c_str(), nullptr, error, sizeof(error)));
  *message = error;
  return model;
}

// ---- the settle recipe (reference section 10, step 1) ----------------------------------------

struct TaskSetup {
  double slide0;
  double extra_height;
  bool has_object;
  std::array<double, 7> object_qpos;
};

TaskSetup SetupFor(const std::string& task) {
  if (task == "reach") return {0.4049, 0.2, false, {}};
  if (task == "push") return {0.405, 0.0, true, {1.25, 0.53, 0.4, 1, 0, 0, 0}};
  if (task == "pick_and_place") return {0.405, 0.2, true, {1.25, 0.53, 0.4, 1, 0, 0, 0}};
  return {0.05, -0.02, true, {1.7, 1.1, 0.41, 1, 0, 0, 0}};  // slide
}

bool IsRobotGeom(const mjModel* m, int geom) {
  const char* name = mj_id2name(m, mjOBJ_BODY, m->geom_bodyid[geom]);
  return name && std::strncmp(name, "robot0:", 7) == 0;
}

int RobotRobotContacts(const mjModel* m, const mjData* d) {
  int count = 0;
  for (int i = 0; i < d->ncon; ++i) {
    count += IsRobotGeom(m, d->contact[i].geom1) && IsRobotGeom(m, d->contact[i].geom2);
  }
  return count;
}

struct Settled {
  std::array<double, 3> grip;   // site robot0:grip after the 200 steps (stale, as in Python)
  int robot_contacts_at_start;  // robot-robot contacts after the two setup forwards
  int robot_contacts_settled;   // robot-robot contacts after a forward at the settled state
  std::vector<std::string> table_touchers;  // names of robot geoms touching table0 when settled
  int data_warnings;                        // mjData warning counters summed
};

/// Runs the environment's one-time setup on m (which it modifies, like Python does) and
/// reports the settled state.
Settled Settle(mjModel* m, const std::string& task) {
  const TaskSetup setup = SetupFor(task);
  MjDataPtr data(mj_makeData(m));
  mjData* d = data.get();
  auto set_joint = [&](const char* name, const double* values, int n) {
    int id = mj_name2id(m, mjOBJ_JOINT, name);
    EXPECT_GE(id, 0) << name;
    if (id >= 0) std::copy(values, values + n, d->qpos + m->jnt_qposadr[id]);
  };
  const double slides[3] = {setup.slide0, 0.48, 0.0};
  set_joint("robot0:slide0", &slides[0], 1);
  set_joint("robot0:slide1", &slides[1], 1);
  set_joint("robot0:slide2", &slides[2], 1);
  if (setup.has_object) set_joint("object0:joint", setup.object_qpos.data(), 7);
  for (int i = 0; i < m->neq; ++i) {
    if (m->eq_type[i] != mjEQ_WELD) continue;
    mjtNum* eq = m->eq_data + i * mjNEQDATA;
    const mjtNum identity[7] = {0, 0, 0, 0, 0, 0, 1};
    std::copy(identity, identity + 7, eq);
  }
  mj_forward(m, d);
  mj_forward(m, d);
  Settled out{};
  out.robot_contacts_at_start = RobotRobotContacts(m, d);
  const int grip = mj_name2id(m, mjOBJ_SITE, "robot0:grip");
  const double offset[3] = {-0.498, 0.005, -0.431 + setup.extra_height};
  for (int k = 0; k < 3; ++k) d->mocap_pos[k] = offset[k] + d->site_xpos[3 * grip + k];
  const double quat[4] = {1, 0, 1, 0};
  std::copy(quat, quat + 4, d->mocap_quat);
  for (int i = 0; i < 200; ++i) mj_step(m, d);
  for (int k = 0; k < 3; ++k) out.grip[k] = d->site_xpos[3 * grip + k];
  mj_forward(m, d);
  out.robot_contacts_settled = RobotRobotContacts(m, d);
  const int table = mj_name2id(m, mjOBJ_BODY, "table0");
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    for (auto [self, other] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}}) {
      if (m->geom_bodyid[other] == table && IsRobotGeom(m, self)) {
        const char* name = mj_id2name(m, mjOBJ_GEOM, self);
        out.table_touchers.emplace_back(name ? name : "(unnamed)");
      }
    }
  }
  for (int i = 0; i < mjNWARNING; ++i) out.data_warnings += d->warning[i].number;
  return out;
}

// ---- comparison helpers ------------------------------------------------------------------------

template <typename T>
void ExpectNearArray(const T* bundled, const T* genuine, int n, double tol,
                     const std::string& what) {
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(bundled[i], genuine[i], tol) << what << "[" << i << "]";
  }
}

template <typename T>
void ExpectEqualArray(const T* bundled, const T* genuine, int n, const std::string& what) {
  for (int i = 0; i < n; ++i) EXPECT_EQ(bundled[i], genuine[i]) << what << "[" << i << "]";
}

std::string Name(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  return name ? name : "";
}

void ExpectSameNames(const mjModel* b, const mjModel* g, mjtObj type, int n, const char* what) {
  for (int i = 0; i < n; ++i) EXPECT_EQ(Name(b, type, i), Name(g, type, i)) << what << " id " << i;
}

/// The colour MuJoCo draws a geom with: its own rgba unless that is the default grey and it
/// has a material, in which case the material's.
std::array<float, 4> DrawnRgba(const mjModel* m, int geom) {
  const float* rgba = m->geom_rgba + 4 * geom;
  const int mat = m->geom_matid[geom];
  const bool default_rgba =
      rgba[0] == 0.5f && rgba[1] == 0.5f && rgba[2] == 0.5f && rgba[3] == 1.0f;
  if (mat >= 0 && default_rgba) rgba = m->mat_rgba + 4 * mat;
  return {rgba[0], rgba[1], rgba[2], rgba[3]};
}

/// Compares everything that matters about one geom (not its id or name).
void ExpectSameGeom(const mjModel* b, int bg, const mjModel* g, int gg, const std::string& what) {
  ASSERT_GE(bg, 0) << what << " missing in the bundled model";
  ASSERT_GE(gg, 0) << what << " missing in the genuine model";
  EXPECT_EQ(b->geom_type[bg], g->geom_type[gg]) << what;
  EXPECT_EQ(b->geom_contype[bg], g->geom_contype[gg]) << what;
  EXPECT_EQ(b->geom_conaffinity[bg], g->geom_conaffinity[gg]) << what;
  EXPECT_EQ(b->geom_condim[bg], g->geom_condim[gg]) << what;
  EXPECT_EQ(Name(b, mjOBJ_BODY, b->geom_bodyid[bg]), Name(g, mjOBJ_BODY, g->geom_bodyid[gg]))
      << what;
  ExpectNearArray(b->geom_size + 3 * bg, g->geom_size + 3 * gg, 3, kTol, what + " size");
  ExpectNearArray(b->geom_pos + 3 * bg, g->geom_pos + 3 * gg, 3, kTol, what + " pos");
  ExpectNearArray(b->geom_quat + 4 * bg, g->geom_quat + 4 * gg, 4, kTol, what + " quat");
  ExpectNearArray(b->geom_friction + 3 * bg, g->geom_friction + 3 * gg, 3, kTol,
                  what + " friction");
  ExpectNearArray(b->geom_solref + mjNREF * bg, g->geom_solref + mjNREF * gg, mjNREF, kTol,
                  what + " solref");
  ExpectNearArray(b->geom_solimp + mjNIMP * bg, g->geom_solimp + mjNIMP * gg, mjNIMP, kTol,
                  what + " solimp");
  EXPECT_NEAR(b->geom_margin[bg], g->geom_margin[gg], kTol) << what;
  EXPECT_NEAR(b->geom_gap[bg], g->geom_gap[gg], kTol) << what;
  EXPECT_EQ(DrawnRgba(b, bg), DrawnRgba(g, gg)) << what << " colour";
  ExpectEqualArray(b->geom_rgba + 4 * bg, g->geom_rgba + 4 * gg, 4, what + " rgba");
  EXPECT_EQ(b->geom_matid[bg] >= 0, g->geom_matid[gg] >= 0) << what << " material";
  if (b->geom_matid[bg] >= 0 && g->geom_matid[gg] >= 0) {
    EXPECT_EQ(Name(b, mjOBJ_MATERIAL, b->geom_matid[bg]),
              Name(g, mjOBJ_MATERIAL, g->geom_matid[gg]))
        << what;
  }
}

int FirstGeomOfBody(const mjModel* m, const char* body) {
  const int id = mj_name2id(m, mjOBJ_BODY, body);
  return id >= 0 && m->body_geomnum[id] > 0 ? m->body_geomadr[id] : -1;
}

std::vector<int> SortedExcludes(const mjModel* m) {
  std::vector<int> v(m->exclude_signature, m->exclude_signature + m->nexclude);
  std::sort(v.begin(), v.end());
  return v;
}

int SkyboxTexture(const mjModel* m) {
  for (int i = 0; i < m->ntex; ++i) {
    if (m->tex_type[i] == mjTEXTURE_SKYBOX) return i;
  }
  return -1;
}

class ModelsTest : public ::testing::TestWithParam<std::string> {
 protected:
  /// Loads the bundled model of the current task; fails the test if it does not compile.
  MjModelPtr LoadBundled() {
    std::string message;
    MjModelPtr m = LoadModel(BundledPath(GetParam()), &message);
    EXPECT_TRUE(m) << BundledPath(GetParam()) << ": " << message;
    return m;
  }
  /// Loads the genuine model of the current task, or returns null when the assets are absent.
  MjModelPtr LoadGenuine() {
    const auto dir = testing::GenuineAssetsDir();
    if (dir.empty()) return nullptr;
    const std::string path = (dir / "fetch" / (GetParam() + ".xml")).string();
    std::string message;
    MjModelPtr m = LoadModel(path, &message);
    EXPECT_TRUE(m) << path << ": " << message;
    return m;
  }
};

TEST_P(ModelsTest, BundledCompilesWithoutWarnings) {
  WarningCapture capture;
  std::string message;
  MjModelPtr m = LoadModel(BundledPath(GetParam()), &message);
  ASSERT_TRUE(m) << message;
  EXPECT_EQ(message, "");
  EXPECT_TRUE(WarningCapture::Messages().empty())
      << WarningCapture::Messages().size()
      << " warning(s), first: " << WarningCapture::Messages()[0];
  EXPECT_EQ(m->nmesh, 0) << "the bundled models are primitives only";
  EXPECT_EQ(Name(m.get(), mjOBJ_SITE, 0), "target0") << "the target marker must be site 0";
}

TEST_P(ModelsTest, BundledSettlesOnItsFingers) {
  MjModelPtr m = LoadBundled();
  ASSERT_TRUE(m);
  WarningCapture capture;
  const Settled s = Settle(m.get(), GetParam());
  EXPECT_EQ(s.robot_contacts_at_start, 0);
  EXPECT_EQ(s.robot_contacts_settled, 0);
  EXPECT_EQ(s.data_warnings, 0);
  EXPECT_TRUE(WarningCapture::Messages().empty());
  // Push and Slide press the gripper onto the table: only the finger boxes may touch it.
  for (const std::string& name : s.table_touchers) {
    EXPECT_TRUE(name == "robot0:r_gripper_finger_link" || name == "robot0:l_gripper_finger_link")
        << name << " touches the table";
  }
  const bool pressed = GetParam() == "push" || GetParam() == "slide";
  EXPECT_EQ(!s.table_touchers.empty(), pressed);
  EXPECT_GT(s.grip[2], 0.4) << "grip site below the table top";
}

TEST_P(ModelsTest, CompiledModelMatchesGenuine) {
  MjModelPtr bundled = LoadBundled();
  ASSERT_TRUE(bundled);
  MjModelPtr genuine = LoadGenuine();
  if (!genuine) GTEST_SKIP() << "genuine Gymnasium-Robotics assets not found";
  const mjModel* b = bundled.get();
  const mjModel* g = genuine.get();

  // Sizes.
  EXPECT_EQ(b->nq, g->nq);
  EXPECT_EQ(b->nv, g->nv);
  EXPECT_EQ(b->nu, g->nu);
  EXPECT_EQ(b->na, g->na);
  ASSERT_EQ(b->nbody, g->nbody);
  ASSERT_EQ(b->njnt, g->njnt);
  ASSERT_EQ(b->nsite, g->nsite);
  ASSERT_EQ(b->ncam, g->ncam);
  ASSERT_EQ(b->nmocap, g->nmocap);
  ASSERT_EQ(b->neq, g->neq);
  ASSERT_EQ(b->nu, g->nu);
  ASSERT_EQ(b->nlight, g->nlight);
  ASSERT_EQ(b->nmat, g->nmat);
  EXPECT_EQ(b->nuser_geom, g->nuser_geom);
  EXPECT_EQ(b->nuser_actuator, g->nuser_actuator);

  // Names by id.
  ExpectSameNames(b, g, mjOBJ_BODY, g->nbody, "body");
  ExpectSameNames(b, g, mjOBJ_JOINT, g->njnt, "joint");
  ExpectSameNames(b, g, mjOBJ_SITE, g->nsite, "site");
  ExpectSameNames(b, g, mjOBJ_CAMERA, g->ncam, "camera");
  ExpectSameNames(b, g, mjOBJ_ACTUATOR, g->nu, "actuator");
  ExpectSameNames(b, g, mjOBJ_MATERIAL, g->nmat, "material");
  ExpectSameNames(b, g, mjOBJ_LIGHT, g->nlight, "light");

  // Bodies: tree, frames, inertials (the mocap body's inertia comes from its geoms; skip it).
  ExpectEqualArray(b->body_parentid, g->body_parentid, g->nbody, "body_parentid");
  ExpectEqualArray(b->body_mocapid, g->body_mocapid, g->nbody, "body_mocapid");
  ExpectEqualArray(b->body_jntnum, g->body_jntnum, g->nbody, "body_jntnum");
  ExpectEqualArray(b->body_jntadr, g->body_jntadr, g->nbody, "body_jntadr");
  ExpectNearArray(b->body_pos, g->body_pos, 3 * g->nbody, kTol, "body_pos");
  ExpectNearArray(b->body_quat, g->body_quat, 4 * g->nbody, kTol, "body_quat");
  for (int i = 0; i < g->nbody; ++i) {
    if (g->body_mocapid[i] >= 0) continue;
    const std::string body = Name(g, mjOBJ_BODY, i);
    EXPECT_NEAR(b->body_mass[i], g->body_mass[i], kTol) << body;
    ExpectNearArray(b->body_inertia + 3 * i, g->body_inertia + 3 * i, 3, kTol, body + " inertia");
    ExpectNearArray(b->body_ipos + 3 * i, g->body_ipos + 3 * i, 3, kTol, body + " ipos");
    ExpectNearArray(b->body_iquat + 4 * i, g->body_iquat + 4 * i, 4, kTol, body + " iquat");
  }

  // Joints and dofs.
  ExpectEqualArray(b->jnt_type, g->jnt_type, g->njnt, "jnt_type");
  ExpectEqualArray(b->jnt_bodyid, g->jnt_bodyid, g->njnt, "jnt_bodyid");
  ExpectEqualArray(b->jnt_qposadr, g->jnt_qposadr, g->njnt, "jnt_qposadr");
  ExpectEqualArray(b->jnt_dofadr, g->jnt_dofadr, g->njnt, "jnt_dofadr");
  ExpectEqualArray(b->jnt_limited, g->jnt_limited, g->njnt, "jnt_limited");
  ExpectNearArray(b->jnt_axis, g->jnt_axis, 3 * g->njnt, kTol, "jnt_axis");
  ExpectNearArray(b->jnt_pos, g->jnt_pos, 3 * g->njnt, kTol, "jnt_pos");
  ExpectNearArray(b->jnt_range, g->jnt_range, 2 * g->njnt, kTol, "jnt_range");
  ExpectNearArray(b->jnt_stiffness, g->jnt_stiffness, g->njnt, kTol, "jnt_stiffness");
  ExpectNearArray(b->jnt_solref, g->jnt_solref, mjNREF * g->njnt, kTol, "jnt_solref");
  ExpectNearArray(b->jnt_solimp, g->jnt_solimp, mjNIMP * g->njnt, kTol, "jnt_solimp");
  ExpectNearArray(b->jnt_margin, g->jnt_margin, g->njnt, kTol, "jnt_margin");
  ExpectNearArray(b->qpos0, g->qpos0, g->nq, kTol, "qpos0");
  ExpectNearArray(b->qpos_spring, g->qpos_spring, g->nq, kTol, "qpos_spring");
  ExpectEqualArray(b->dof_bodyid, g->dof_bodyid, g->nv, "dof_bodyid");
  ExpectEqualArray(b->dof_parentid, g->dof_parentid, g->nv, "dof_parentid");
  ExpectNearArray(b->dof_damping, g->dof_damping, g->nv, kTol, "dof_damping");
  ExpectNearArray(b->dof_armature, g->dof_armature, g->nv, kTol, "dof_armature");
  ExpectNearArray(b->dof_frictionloss, g->dof_frictionloss, g->nv, kTol, "dof_frictionloss");

  // Sites and cameras.
  ExpectEqualArray(b->site_type, g->site_type, g->nsite, "site_type");
  ExpectEqualArray(b->site_bodyid, g->site_bodyid, g->nsite, "site_bodyid");
  ExpectNearArray(b->site_pos, g->site_pos, 3 * g->nsite, kTol, "site_pos");
  ExpectNearArray(b->site_quat, g->site_quat, 4 * g->nsite, kTol, "site_quat");
  ExpectNearArray(b->site_size, g->site_size, 3 * g->nsite, kTol, "site_size");
  ExpectEqualArray(b->site_rgba, g->site_rgba, 4 * g->nsite, "site_rgba");
  ExpectEqualArray(b->cam_bodyid, g->cam_bodyid, g->ncam, "cam_bodyid");
  ExpectEqualArray(b->cam_mode, g->cam_mode, g->ncam, "cam_mode");
  ExpectNearArray(b->cam_pos, g->cam_pos, 3 * g->ncam, kTol, "cam_pos");
  ExpectNearArray(b->cam_quat, g->cam_quat, 4 * g->ncam, kTol, "cam_quat");
  ExpectNearArray(b->cam_fovy, g->cam_fovy, g->ncam, kTol, "cam_fovy");

  // Equality (the mocap weld) and contact excludes.
  ExpectEqualArray(b->eq_type, g->eq_type, g->neq, "eq_type");
  ExpectEqualArray(b->eq_obj1id, g->eq_obj1id, g->neq, "eq_obj1id");
  ExpectEqualArray(b->eq_obj2id, g->eq_obj2id, g->neq, "eq_obj2id");
  ExpectEqualArray(b->eq_active, g->eq_active, g->neq, "eq_active");
  ExpectNearArray(b->eq_solref, g->eq_solref, mjNREF * g->neq, kTol, "eq_solref");
  ExpectNearArray(b->eq_solimp, g->eq_solimp, mjNIMP * g->neq, kTol, "eq_solimp");
  ExpectNearArray(b->eq_data, g->eq_data, mjNEQDATA * g->neq, kEqDataTol, "eq_data");
  EXPECT_EQ(SortedExcludes(b), SortedExcludes(g));

  // Actuators (PickAndPlace's finger servos).
  ExpectEqualArray(b->actuator_trntype, g->actuator_trntype, g->nu, "actuator_trntype");
  ExpectEqualArray(b->actuator_trnid, g->actuator_trnid, 2 * g->nu, "actuator_trnid");
  ExpectEqualArray(b->actuator_dyntype, g->actuator_dyntype, g->nu, "actuator_dyntype");
  ExpectEqualArray(b->actuator_gaintype, g->actuator_gaintype, g->nu, "actuator_gaintype");
  ExpectEqualArray(b->actuator_biastype, g->actuator_biastype, g->nu, "actuator_biastype");
  ExpectEqualArray(b->actuator_ctrllimited, g->actuator_ctrllimited, g->nu, "actuator_ctrllimited");
  ExpectEqualArray(b->actuator_forcelimited, g->actuator_forcelimited, g->nu,
                   "actuator_forcelimited");
  ExpectNearArray(b->actuator_gainprm, g->actuator_gainprm, mjNGAIN * g->nu, kTol,
                  "actuator_gainprm");
  ExpectNearArray(b->actuator_biasprm, g->actuator_biasprm, mjNBIAS * g->nu, kTol,
                  "actuator_biasprm");
  ExpectNearArray(b->actuator_ctrlrange, g->actuator_ctrlrange, 2 * g->nu, kTol,
                  "actuator_ctrlrange");
  ExpectNearArray(b->actuator_gear, g->actuator_gear, 6 * g->nu, kTol, "actuator_gear");

  // Options and statistics.
  EXPECT_EQ(b->opt.timestep, g->opt.timestep);
  ExpectEqualArray(b->opt.gravity, g->opt.gravity, 3, "gravity");
  EXPECT_EQ(b->opt.integrator, g->opt.integrator);
  EXPECT_EQ(b->opt.cone, g->opt.cone);
  EXPECT_EQ(b->opt.solver, g->opt.solver);
  EXPECT_EQ(b->opt.jacobian, g->opt.jacobian);
  EXPECT_EQ(b->opt.iterations, g->opt.iterations);
  EXPECT_EQ(b->opt.tolerance, g->opt.tolerance);
  EXPECT_EQ(b->opt.impratio, g->opt.impratio);
  EXPECT_EQ(b->opt.disableflags, g->opt.disableflags);
  EXPECT_EQ(b->opt.enableflags, g->opt.enableflags);
  EXPECT_NEAR(b->stat.extent, g->stat.extent, 1e-8);
  EXPECT_NEAR(b->stat.meansize, g->stat.meansize, 1e-8);
  ExpectNearArray(b->stat.center, g->stat.center, 3, 1e-8, "stat.center");
  // Derived from the inertias, so equal too; the solver scales its tolerance with meaninertia.
  EXPECT_NEAR(b->stat.meaninertia / g->stat.meaninertia, 1.0, 1e-9);
  EXPECT_NEAR(b->stat.meanmass / g->stat.meanmass, 1.0, 1e-9);
  EXPECT_EQ(b->vis.global.fovy, g->vis.global.fovy);
  EXPECT_EQ(b->vis.map.znear, g->vis.map.znear);
  EXPECT_EQ(b->vis.map.zfar, g->vis.map.zfar);

  // Scene items: floor, table, object, finger boxes, mocap cross, light, materials, sky.
  ExpectSameGeom(b, mj_name2id(b, mjOBJ_GEOM, "floor0"), g, mj_name2id(g, mjOBJ_GEOM, "floor0"),
                 "floor0");
  ExpectSameGeom(b, FirstGeomOfBody(b, "table0"), g, FirstGeomOfBody(g, "table0"), "table geom");
  if (GetParam() != "reach") {
    ExpectSameGeom(b, mj_name2id(b, mjOBJ_GEOM, "object0"), g, mj_name2id(g, mjOBJ_GEOM, "object0"),
                   "object0");
  }
  for (const char* finger : {"robot0:r_gripper_finger_link", "robot0:l_gripper_finger_link"}) {
    ExpectSameGeom(b, mj_name2id(b, mjOBJ_GEOM, finger), g, mj_name2id(g, mjOBJ_GEOM, finger),
                   finger);
  }
  const int mocap_body = mj_name2id(g, mjOBJ_BODY, "robot0:mocap");
  ASSERT_EQ(b->body_geomnum[mocap_body], g->body_geomnum[mocap_body]);
  for (int k = 0; k < g->body_geomnum[mocap_body]; ++k) {
    ExpectSameGeom(b, b->body_geomadr[mocap_body] + k, g, g->body_geomadr[mocap_body] + k,
                   "mocap geom " + std::to_string(k));
  }
  ExpectEqualArray(b->light_directional, g->light_directional, g->nlight, "light_directional");
  ExpectEqualArray(b->light_castshadow, g->light_castshadow, g->nlight, "light_castshadow");
  ExpectEqualArray(b->light_active, g->light_active, g->nlight, "light_active");
  ExpectEqualArray(b->light_bodyid, g->light_bodyid, g->nlight, "light_bodyid");
  ExpectNearArray(b->light_pos, g->light_pos, 3 * g->nlight, kTol, "light_pos");
  ExpectNearArray(b->light_dir, g->light_dir, 3 * g->nlight, kTol, "light_dir");
  ExpectEqualArray(b->light_ambient, g->light_ambient, 3 * g->nlight, "light_ambient");
  ExpectEqualArray(b->light_diffuse, g->light_diffuse, 3 * g->nlight, "light_diffuse");
  ExpectEqualArray(b->light_specular, g->light_specular, 3 * g->nlight, "light_specular");
  ExpectEqualArray(b->mat_rgba, g->mat_rgba, 4 * g->nmat, "mat_rgba");
  ExpectEqualArray(b->mat_specular, g->mat_specular, g->nmat, "mat_specular");
  ExpectEqualArray(b->mat_shininess, g->mat_shininess, g->nmat, "mat_shininess");
  ExpectEqualArray(b->mat_reflectance, g->mat_reflectance, g->nmat, "mat_reflectance");
  ExpectEqualArray(b->mat_emission, g->mat_emission, g->nmat, "mat_emission");
  const int bsky = SkyboxTexture(b);
  const int gsky = SkyboxTexture(g);
  ASSERT_GE(bsky, 0);
  ASSERT_GE(gsky, 0);
  ASSERT_EQ(b->tex_width[bsky], g->tex_width[gsky]);
  ASSERT_EQ(b->tex_height[bsky], g->tex_height[gsky]);
  EXPECT_EQ(0, std::memcmp(b->tex_rgb + b->tex_adr[bsky], g->tex_rgb + g->tex_adr[gsky],
                           3 * static_cast<size_t>(g->tex_width[gsky]) * g->tex_height[gsky]))
      << "skybox pixels differ";

  // Robot colours: every primitive standing in for a mesh is drawn like that mesh.
  for (int gg = 0; gg < g->ngeom; ++gg) {
    if (g->geom_type[gg] != mjGEOM_MESH) continue;
    const int body = g->geom_bodyid[gg];
    ASSERT_GT(b->body_geomnum[body], 0) << Name(g, mjOBJ_BODY, body) << " has no geoms";
    for (int k = 0; k < b->body_geomnum[body]; ++k) {
      const int bg = b->body_geomadr[body] + k;
      const std::string what = Name(b, mjOBJ_GEOM, bg);
      EXPECT_EQ(DrawnRgba(b, bg), DrawnRgba(g, gg)) << what;
      EXPECT_EQ(b->geom_contype[bg], g->geom_contype[gg]) << what;
      EXPECT_EQ(b->geom_conaffinity[bg], g->geom_conaffinity[gg]) << what;
      EXPECT_EQ(b->geom_condim[bg], g->geom_condim[gg]) << what;
      EXPECT_NEAR(b->geom_margin[bg], g->geom_margin[gg], kTol) << what;
      ExpectNearArray(b->geom_friction + 3 * bg, g->geom_friction + 3 * gg, 3, kTol,
                      what + " friction");
      ExpectNearArray(b->geom_solref + mjNREF * bg, g->geom_solref + mjNREF * gg, mjNREF, kTol,
                      what + " solref");
      ExpectNearArray(b->geom_solimp + mjNIMP * bg, g->geom_solimp + mjNIMP * gg, mjNIMP, kTol,
                      what + " solimp");
      EXPECT_EQ(Name(b, mjOBJ_MATERIAL, b->geom_matid[bg]),
                Name(g, mjOBJ_MATERIAL, g->geom_matid[gg]))
          << what;
    }
  }
}

TEST_P(ModelsTest, SettledGripMatchesGenuine) {
  MjModelPtr bundled = LoadBundled();
  ASSERT_TRUE(bundled);
  MjModelPtr genuine = LoadGenuine();
  if (!genuine) GTEST_SKIP() << "genuine Gymnasium-Robotics assets not found";
  const Settled b = Settle(bundled.get(), GetParam());
  const Settled g = Settle(genuine.get(), GetParam());
  double worst = 0;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(b.grip[k], g.grip[k], kSettleTol) << "grip site axis " << k;
    worst = std::max(worst, std::fabs(b.grip[k] - g.grip[k]));
  }
  std::cout << "[ models ] " << GetParam() << " settled grip: bundled (" << b.grip[0] << ", "
            << b.grip[1] << ", " << b.grip[2] << ") genuine (" << g.grip[0] << ", " << g.grip[1]
            << ", " << g.grip[2] << ") max |diff| " << worst << " m\n";
  RecordProperty("max_abs_diff_m", std::to_string(worst));
  // The primitives must not add self-contacts that the meshes' convex hulls do not have.
  EXPECT_LE(b.robot_contacts_at_start, g.robot_contacts_at_start);
  EXPECT_LE(b.robot_contacts_settled, g.robot_contacts_settled);
  EXPECT_EQ(b.table_touchers.empty(), g.table_touchers.empty());
}

INSTANTIATE_TEST_SUITE_P(Tasks, ModelsTest,
                         ::testing::Values("reach", "push", "pick_and_place", "slide"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
}  // namespace fetchscope
