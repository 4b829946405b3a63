#include "src/fetch_env.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <random>
#include <set>

#include "base/errors.h"

namespace fetchscope {
namespace {

int RequireId(const mjModel* m, mjtObj type, const char* name, const std::string& file) {
  int id = mj_name2id(m, type, name);
  if (id < 0) {
    throw RunError("model '" + file + "' has no " + mju_type2Str(type) + " named '" + name +
                   "': it is not a Fetch model");
  }
  return id;
}

// Euclidean norm over 3 components in numpy's order: sqrt((x0^2 + x1^2) + x2^2).
double Norm3(double dx, double dy, double dz) { return std::sqrt(dx * dx + dy * dy + dz * dz); }

void ErrorHandler(const char* msg) {
  std::fprintf(stderr, "fetchscope: error: MuJoCo: %s\n", msg);
  std::fflush(stderr);
  std::_Exit(1);
}

void WarningHandler(const char* msg) {
  static std::mutex mutex;
  static std::set<std::string> seen;
  std::lock_guard<std::mutex> lock(mutex);
  if (seen.insert(msg).second) std::fprintf(stderr, "fetchscope: warning: MuJoCo: %s\n", msg);
}

}  // namespace

double GoalDistance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return Norm3(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

void InstallMujocoHandlers() {
  mju_user_error = ErrorHandler;
  mju_user_warning = WarningHandler;
}

std::array<double, 4> Euler2Quat(const std::array<double, 3>& euler) {
  const double ai = euler[2] / 2, aj = -euler[1] / 2, ak = euler[0] / 2;
  const double si = std::sin(ai), sj = std::sin(aj), sk = std::sin(ak);
  const double ci = std::cos(ai), cj = std::cos(aj), ck = std::cos(ak);
  const double cc = ci * ck, cs = ci * sk, sc = si * ck, ss = si * sk;
  return {cj * cc + sj * ss, cj * cs - sj * sc, -(cj * ss + sj * cc), cj * sc - sj * cs};
}

std::array<double, 3> Mat2Euler(const double* mat) {
  // M[r][c] = mat[3r + c]; thresholds and signs as in gymnasium_robotics/utils/rotations.py.
  const double eps4 = 4 * 2.220446049250313e-16;
  const double cy = std::sqrt(mat[8] * mat[8] + mat[5] * mat[5]);
  std::array<double, 3> e;
  if (cy > eps4) {
    e[2] = -std::atan2(mat[1], mat[0]);
    e[1] = -std::atan2(-mat[2], cy);
    e[0] = -std::atan2(mat[5], mat[8]);
  } else {
    e[2] = -std::atan2(-mat[3], mat[4]);
    e[1] = -std::atan2(-mat[2], cy);
    e[0] = 0.0;
  }
  return e;
}

FetchEnv::FetchEnv(const EnvSpec& spec, const AssetSource& assets)
    : spec_(spec), assets_(assets), model_path_(ModelPath(assets, spec)) {
  char error[1024] = "";
  model_.reset(mj_loadXML(model_path_.c_str(), nullptr, error, sizeof(error)));
  if (!model_) {
    std::string msg = error;
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
    for (char& c : msg) {
      if (c == '\n') c = ' ';
    }
    throw RunError("cannot load model '" + model_path_ + "': " + msg);
  }
  data_.reset(mj_makeData(model_.get()));
  if (!data_) throw RunError("cannot allocate mjData for '" + model_path_ + "'");
  Setup();
}

void FetchEnv::Setup() {
  mjModel* m = model_.get();
  mjData* d = data_.get();
  grip_site_ = RequireId(m, mjOBJ_SITE, "robot0:grip", model_path_);
  gripper_body_ = RequireId(m, mjOBJ_BODY, "robot0:gripper_link", model_path_);
  mocap_id_ = m->body_mocapid[RequireId(m, mjOBJ_BODY, "robot0:mocap", model_path_)];
  if (mocap_id_ < 0)
    throw RunError("model '" + model_path_ + "': robot0:mocap is not a mocap body");
  const int l_joint = RequireId(m, mjOBJ_JOINT, "robot0:l_gripper_finger_joint", model_path_);
  const int r_joint = RequireId(m, mjOBJ_JOINT, "robot0:r_gripper_finger_joint", model_path_);
  l_finger_qpos_ = m->jnt_qposadr[l_joint];
  r_finger_qpos_ = m->jnt_qposadr[r_joint];
  l_finger_dof_ = m->jnt_dofadr[l_joint];
  r_finger_dof_ = m->jnt_dofadr[r_joint];
  if (spec_.has_object) {
    object_site_ = RequireId(m, mjOBJ_SITE, "object0", model_path_);
    object_qpos_ = m->jnt_qposadr[RequireId(m, mjOBJ_JOINT, "object0:joint", model_path_)];
  }
  contact_bodies_ = FindContactBodies(m);
  jacp_.assign(3 * m->nv, 0.0);
  jacr_.assign(3 * m->nv, 0.0);

  // 1. initial joint values, in the registered order
  for (const auto& [name, values] : spec_.initial_qpos) {
    const int j = RequireId(m, mjOBJ_JOINT, name.c_str(), model_path_);
    for (size_t i = 0; i < values.size(); ++i) d->qpos[m->jnt_qposadr[j] + i] = values[i];
  }
  // 2. reset_mocap_welds: identity weld (anchor 0, offset 0, quaternion w = 1), then forward
  for (int i = 0; i < m->neq; ++i) {
    if (m->eq_type[i] != mjEQ_WELD) continue;
    const double identity[7] = {0, 0, 0, 0, 0, 0, 1};
    std::copy(identity, identity + 7, m->eq_data + i * mjNEQDATA);
  }
  mj_forward(m, d);
  mj_forward(m, d);
  // 3. mocap target above (or, for Push/Slide, pressed onto) the table, pointing down
  const double* grip = d->site_xpos + 3 * grip_site_;
  d->mocap_pos[3 * mocap_id_ + 0] = -0.498 + grip[0];
  d->mocap_pos[3 * mocap_id_ + 1] = 0.005 + grip[1];
  d->mocap_pos[3 * mocap_id_ + 2] = (-0.431 + spec_.gripper_extra_height) + grip[2];
  const double quat[4] = {1.0, 0.0, 1.0, 0.0};
  std::copy(quat, quat + 4, d->mocap_quat + 4 * mocap_id_);
  // 4. settle: 10 x n_substeps physics steps, no forward afterwards (positions one substep stale)
  for (int i = 0; i < 10 * spec_.n_substeps; ++i) mj_step(m, d);
  for (int k = 0; k < 3; ++k) initial_gripper_xpos_[k] = d->site_xpos[3 * grip_site_ + k];
  if (spec_.has_object) height_offset_ = d->site_xpos[3 * object_site_ + 2];
  // 5. the state every reset restores
  initial_time_ = d->time;
  initial_qpos_.assign(d->qpos, d->qpos + m->nq);
  initial_qvel_.assign(d->qvel, d->qvel + m->nv);
}

Observation FetchEnv::Reset(std::optional<uint64_t> seed) {
  if (seed) {
    rng_.emplace(*seed);
  } else if (!rng_) {
    std::random_device rd;  // Gymnasium seeds from OS entropy when never seeded
    rng_.emplace((static_cast<uint64_t>(rd()) << 32) | rd());
  }
  mjModel* m = model_.get();
  mjData* d = data_.get();
  RestoreInitialState();
  if (spec_.has_object) {
    const double gx = initial_gripper_xpos_[0], gy = initial_gripper_xpos_[1];
    double x = gx, y = gy;
    while (std::sqrt((x - gx) * (x - gx) + (y - gy) * (y - gy)) < 0.1) {
      x = gx + rng_->Uniform(-spec_.obj_range, spec_.obj_range);
      y = gy + rng_->Uniform(-spec_.obj_range, spec_.obj_range);
    }
    d->qpos[object_qpos_ + 0] = x;
    d->qpos[object_qpos_ + 1] = y;
  }
  KeepCallState(false);
  mj_forward(m, d);
  goal_ = SampleGoal();
  elapsed_steps_ = 0;
  has_reset_ = true;
  return Observe();
}

// _reset_sim up to the object placement: mj_resetData, then time, qpos, qvel as saved
void FetchEnv::RestoreInitialState() {
  mjData* d = data_.get();
  mj_resetData(model_.get(), d);
  d->time = initial_time_;
  std::copy(initial_qpos_.begin(), initial_qpos_.end(), d->qpos);
  std::copy(initial_qvel_.begin(), initial_qvel_.end(), d->qvel);
}

Observation FetchEnv::ResetTo(const std::array<double, 3>& goal,
                              const std::optional<ObjectPose>& object) {
  mjModel* m = model_.get();
  mjData* d = data_.get();
  RestoreInitialState();
  if (spec_.has_object && object) {
    double* q = d->qpos + object_qpos_;
    for (int k = 0; k < 3; ++k) q[k] = object->position[k];
    // kinematics alone (no solver, so the warm start stays as mj_resetData left it): does the
    // settled quaternion give these angles? A reset never rotates the object, so it usually does
    mj_kinematics(m, d);
    const std::array<double, 3> settled = Mat2Euler(d->site_xmat + 9 * object_site_);
    bool same = true;
    for (int k = 0; k < 3; ++k) same = same && std::fabs(settled[k] - object->euler[k]) <= 1e-12;
    if (!same) {
      const std::array<double, 4> quat = Euler2Quat(object->euler);
      std::copy(quat.begin(), quat.end(), q + 3);
    }
  }
  KeepCallState(false);
  mj_forward(m, d);
  goal_ = goal;
  elapsed_steps_ = 0;
  has_reset_ = true;
  return Observe();
}

std::array<double, 3> FetchEnv::SampleGoal() {
  std::array<double, 3> goal;
  for (int k = 0; k < 3; ++k) {
    goal[k] = initial_gripper_xpos_[k] + rng_->Uniform(-spec_.target_range, spec_.target_range);
  }
  if (!spec_.has_object) return goal;
  for (int k = 0; k < 3; ++k) goal[k] += spec_.target_offset[k];
  goal[2] = height_offset_;
  if (spec_.target_in_the_air && rng_->NextDouble() < 0.5) goal[2] += rng_->Uniform(0, 0.45);
  return goal;
}

StepResult FetchEnv::Step(const Action& action) {
  if (!has_reset_) throw RunError("step() before reset(): reset the environment first");
  mjModel* m = model_.get();
  mjData* d = data_.get();
  StepResult result;

  // clip to the float32 Box bounds, scale positions by 0.05 in the action's own precision
  double pos[3], grip;
  if (action.is_float32) {
    float a[4];
    for (int i = 0; i < 4; ++i) a[i] = std::clamp(static_cast<float>(action.value[i]), -1.0f, 1.0f);
    for (int i = 0; i < 3; ++i) pos[i] = static_cast<double>(a[i] * 0.05f);
    grip = a[3];
    for (int i = 0; i < 4; ++i) result.applied[i] = a[i];
  } else {
    double a[4];
    for (int i = 0; i < 4; ++i) a[i] = std::clamp(action.value[i], -1.0, 1.0);
    for (int i = 0; i < 3; ++i) pos[i] = a[i] * 0.05;
    grip = a[3];
    for (int i = 0; i < 4; ++i) result.applied[i] = a[i];
  }
  if (spec_.block_gripper) grip = 0.0;

  // ctrl_set_action: position servos get current finger position + command
  for (int i = 0; i < std::min(m->nu, 2); ++i) {
    if (m->actuator_biastype[i] == mjBIAS_NONE) {
      d->ctrl[i] = grip;
    } else {
      d->ctrl[i] = d->qpos[m->jnt_qposadr[m->actuator_trnid[2 * i]]] + grip;
    }
  }
  // mocap_set_action: re-anchor the mocap on the welded body (as data holds it), then add deltas
  for (int i = 0; i < m->neq; ++i) {
    if (m->eq_type[i] != mjEQ_WELD) continue;
    int mocap = m->body_mocapid[m->eq_obj1id[i]];
    int body = m->eq_obj2id[i];
    if (mocap == -1) {
      mocap = m->body_mocapid[m->eq_obj2id[i]];
      body = m->eq_obj1id[i];
    }
    if (mocap == -1) continue;
    std::copy(d->xpos + 3 * body, d->xpos + 3 * body + 3, d->mocap_pos + 3 * mocap);
    std::copy(d->xquat + 4 * body, d->xquat + 4 * body + 4, d->mocap_quat + 4 * mocap);
  }
  for (int k = 0; k < m->nmocap; ++k) {
    for (int i = 0; i < 3; ++i) d->mocap_pos[3 * k + i] = d->mocap_pos[3 * k + i] + pos[i];
    d->mocap_quat[4 * k + 0] += 1.0;
    d->mocap_quat[4 * k + 2] += 1.0;
  }
  for (int i = 0; i < spec_.n_substeps; ++i) {
    if (i == spec_.n_substeps - 1) KeepCallState(true);
    mj_step(m, d);
  }
  StepCallback();
  ++elapsed_steps_;
  result.obs = Observe();
  result.is_success = IsSuccess(result.obs.achieved_goal, goal_);
  result.reward = ComputeReward(result.obs.achieved_goal, goal_);
  result.truncated = elapsed_steps_ >= spec_.max_episode_steps;
  return result;
}

std::optional<ContactSignals> FetchEnv::Contacts() const {
  if (!contact_signals_) return std::nullopt;
  return ReadContacts(model_.get(), data_.get(), contact_bodies_);
}

void FetchEnv::StepCallback() {
  if (!spec_.block_gripper) return;
  mjData* d = data_.get();
  d->qpos[l_finger_qpos_] = 0.0;
  d->qpos[r_finger_qpos_] = 0.0;
  mj_forward(model_.get(), d);
}

double FetchEnv::ComputeReward(const std::array<double, 3>& a,
                               const std::array<double, 3>& b) const {
  const double dist = GoalDistance(a, b);
  if (spec_.dense) return -dist;
  return dist > spec_.distance_threshold ? -1.0 : -0.0;
}

bool FetchEnv::IsSuccess(const std::array<double, 3>& a, const std::array<double, 3>& b) const {
  return GoalDistance(a, b) < spec_.distance_threshold;
}

Observation FetchEnv::Observe() const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  const double dt = this->dt();
  const int nv = m->nv;
  auto velocity = [&](const std::vector<double>& jac, int row) {
    double v = 0;
    for (int j = 0; j < nv; ++j) v += jac[row * nv + j] * d->qvel[j];
    return v;
  };

  Observation obs;
  const double* grip = d->site_xpos + 3 * grip_site_;
  mj_jacSite(m, d, jacp_.data(), nullptr, grip_site_);
  double grip_velp[3];
  for (int i = 0; i < 3; ++i) grip_velp[i] = velocity(jacp_, i) * dt;
  const double gripper_state[2] = {d->qpos[r_finger_qpos_], d->qpos[l_finger_qpos_]};
  const double gripper_vel[2] = {d->qvel[r_finger_dof_] * dt, d->qvel[l_finger_dof_] * dt};

  // the order src/observation_layout.h declares (its test checks it against this)
  auto& o = obs.observation;
  o.insert(o.end(), grip, grip + 3);
  if (spec_.has_object) {
    const double* object = d->site_xpos + 3 * object_site_;
    mj_jacSite(m, d, jacp_.data(), jacr_.data(), object_site_);
    double velp[3], velr[3];
    for (int i = 0; i < 3; ++i) {
      velp[i] = velocity(jacp_, i) * dt - grip_velp[i];
      velr[i] = velocity(jacr_, i) * dt;
    }
    const std::array<double, 3> rot = Mat2Euler(d->site_xmat + 9 * object_site_);
    o.insert(o.end(), object, object + 3);
    for (int i = 0; i < 3; ++i) o.push_back(object[i] - grip[i]);
    o.insert(o.end(), gripper_state, gripper_state + 2);
    o.insert(o.end(), rot.begin(), rot.end());
    o.insert(o.end(), velp, velp + 3);
    o.insert(o.end(), velr, velr + 3);
    o.insert(o.end(), grip_velp, grip_velp + 3);
    o.insert(o.end(), gripper_vel, gripper_vel + 2);
    for (int i = 0; i < 3; ++i) obs.achieved_goal[i] = object[i];
  } else {
    o.insert(o.end(), gripper_state, gripper_state + 2);
    o.insert(o.end(), grip_velp, grip_velp + 3);
    o.insert(o.end(), gripper_vel, gripper_vel + 2);
    for (int i = 0; i < 3; ++i) obs.achieved_goal[i] = grip[i];
  }
  obs.desired_goal = goal_;
  return obs;
}

}  // namespace fetchscope
