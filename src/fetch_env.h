// One Fetch v4 environment on MuJoCo 2.2.2: setup, reset, step, observation, reward,
// exactly as Gymnasium-Robotics does it (see the reference's sections 2 to 6 and 11).
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "src/action.h"
#include "src/assets.h"
#include "src/contacts.h"
#include "src/env_spec.h"
#include "src/mj_handles.h"
#include "src/rng.h"

namespace fetchscope {

/// The goal-env observation dict.
struct Observation {
  std::vector<double> observation;      ///< 10 values (Reach) or 25 (object tasks)
  std::array<double, 3> achieved_goal;  ///< grip site (Reach) or object site position, m
  std::array<double, 3> desired_goal;   ///< the episode's goal, m
};

/// What step() returns (terminated is always false for Fetch).
struct StepResult {
  Observation obs;                  ///< observation after the step
  double reward = 0;                ///< sparse: -1.0 or -0.0; dense: -distance
  bool is_success = false;          ///< distance < threshold
  bool truncated = false;           ///< TimeLimit: elapsed steps reached max_episode_steps
  std::array<double, 4> applied{};  ///< the action after clipping, as promoted to double
};

/// The object's pose at a reset as the observation gives it: object_pos (obs[3:6]) and
/// object_rot, the Euler angles of mat2euler (obs[11:14]).
struct ObjectPose {
  std::array<double, 3> position{};  ///< m, world
  std::array<double, 3> euler{};     ///< rad, as mat2euler gives them
};

/// A way back to one state of an environment, exactly (FetchEnv::Checkpoint): MuJoCo's state
/// just before the last call that computed the env's mjData (a step's last substep, or a reset's
/// mj_forward) and the env's own (goal, steps taken, generator). Restoring repeats that one call,
/// so every value the data derives (positions, which a step leaves one substep stale; contacts
/// and their forces) is bit for bit what the env held, and stepping on gives the same episode.
struct EnvCheckpoint {
  /// time, qpos, qvel, act, ctrl, qacc_warmstart, mocap_pos, mocap_quat, qfrc_applied,
  /// xfrc_applied, in that order, before the call
  std::vector<double> sim;
  bool after_step = false;  ///< the call: a step's last mj_step (and its callback); else mj_forward
  std::array<double, 3> goal{};       ///< the episode's goal
  int elapsed_steps = 0;              ///< steps since the reset
  std::optional<NumpyGenerator> rng;  ///< the reset generator as it stood
};

/// A Fetch environment. Not copyable; one per thread.
class FetchEnv {
 public:
  /// Loads the model from `assets` and runs the one-time setup (settling included).
  /// Throws RunError with MuJoCo's message if the model cannot be loaded.
  FetchEnv(const EnvSpec& spec, const AssetSource& assets);
  FetchEnv(const FetchEnv&) = delete;
  FetchEnv& operator=(const FetchEnv&) = delete;

  /// env.reset(seed=...): a seed restarts the generator; none continues it.
  Observation Reset(std::optional<uint64_t> seed = std::nullopt);

  /// A reset to a known start instead of a sampled one (re-rendering a dataset episode that
  /// was reset without a seed): _reset_sim with the object at `object` (object tasks; ignored
  /// for Reach), one mj_forward as reset does, then goal = `goal`. The generator is untouched.
  /// The settled quaternion is kept where its Euler angles are `object->euler` to within
  /// rounding (1e-12 rad: another atan2, e.g. numpy's SIMD one, may round the last bits
  /// differently; a reset never rotates the object, so the angles it recorded are the settled
  /// quaternion's).
  Observation ResetTo(const std::array<double, 3>& goal, const std::optional<ObjectPose>& object);

  /// The reset generator as it stands (nullopt before the first Reset), and setting it: the next
  /// Reset() without a seed continues from it, as the env that made a dataset did.
  const std::optional<NumpyGenerator>& generator() const { return rng_; }
  void set_generator(const NumpyGenerator& generator) { rng_ = generator; }

  /// env.step(action) with TimeLimit semantics. Requires a prior Reset().
  StepResult Step(const Action& action);

  /// Keeps, from now on, what Checkpoint needs at every Reset, ResetTo and Step (a copy of a few
  /// hundred numbers per call). Off by default; it never changes what the env computes.
  void EnableCheckpoints() { checkpoints_ = true; }
  /// The current state as a checkpoint. Throws RunError before the first reset made after
  /// EnableCheckpoints.
  EnvCheckpoint Checkpoint() const;
  /// Returns to `checkpoint` (taken on this env, or on one of the same spec and assets): the
  /// data, goal, step count and generator are then exactly as they were.
  void Restore(const EnvCheckpoint& checkpoint);

  /// Makes Contacts() read the state's contacts from now on (record/rollout --signals contacts):
  /// the episodes' rows then carry them. Reading never changes the simulation.
  void EnableContactSignals() { contact_signals_ = true; }
  /// The contacts of the current state (ReadContacts), or nullopt unless EnableContactSignals.
  std::optional<ContactSignals> Contacts() const;
  /// The bodies that name the contact pairs in this model.
  const ContactBodies& contact_bodies() const { return contact_bodies_; }

  /// compute_reward(achieved_goal, desired_goal): pure function of the two goals.
  double ComputeReward(const std::array<double, 3>& achieved,
                       const std::array<double, 3>& desired) const;
  /// _is_success: distance < threshold.
  bool IsSuccess(const std::array<double, 3>& achieved, const std::array<double, 3>& desired) const;

  /// The current observation (no simulation work).
  Observation Observe() const;

  const EnvSpec& spec() const { return spec_; }                ///< the registered id
  const AssetSource& assets() const { return assets_; }        ///< where the model came from
  std::string model_path() const { return model_path_; }       ///< the MJCF file loaded
  mjModel* model() const { return model_.get(); }              ///< the compiled model
  mjData* data() const { return data_.get(); }                 ///< the live state
  const std::array<double, 3>& goal() const { return goal_; }  ///< current goal, m
  int elapsed_steps() const { return elapsed_steps_; }         ///< steps since reset
  double dt() const { return model_->opt.timestep * spec_.n_substeps; }  ///< s per env step
  const std::array<double, 3>& initial_gripper_xpos() const { return initial_gripper_xpos_; }
  double height_offset() const { return height_offset_; }  ///< object z after settling
  int grip_site() const { return grip_site_; }             ///< site id of robot0:grip
  int gripper_body() const { return gripper_body_; }       ///< body id of robot0:gripper_link

 private:
  void Setup();
  void RestoreInitialState();
  // With checkpoints on: keeps MuJoCo's state now, before the call that finishes a reset
  // (`step` false: mj_forward) or a step (true: its last mj_step)
  void KeepCallState(bool step);
  // A step's end after its substeps (_step_callback): with a blocked gripper, the fingers closed
  // and a forward pass
  void StepCallback();
  std::array<double, 3> SampleGoal();

  EnvSpec spec_;
  AssetSource assets_;
  std::string model_path_;
  MjModelPtr model_;
  MjDataPtr data_;
  std::optional<NumpyGenerator> rng_;

  int grip_site_ = -1;
  int object_site_ = -1;
  int gripper_body_ = -1;
  int mocap_id_ = -1;
  int object_qpos_ = -1;
  int l_finger_qpos_ = -1, r_finger_qpos_ = -1;
  int l_finger_dof_ = -1, r_finger_dof_ = -1;

  double initial_time_ = 0;
  std::vector<double> initial_qpos_, initial_qvel_;
  std::array<double, 3> initial_gripper_xpos_{};
  double height_offset_ = 0;
  std::array<double, 3> goal_{};
  int elapsed_steps_ = 0;
  bool has_reset_ = false;
  bool checkpoints_ = false;
  bool contact_signals_ = false;
  ContactBodies contact_bodies_;
  std::vector<double> call_state_;  // KeepCallState's copy, empty until a reset keeps one
  bool call_is_step_ = false;
  mutable std::vector<double> jacp_, jacr_;
};

/// Installs MuJoCo's error and warning handlers (errors print one line and exit 1; warnings
/// are printed once each on stderr). Call once at program start.
void InstallMujocoHandlers();

/// || a - b ||, summed in numpy's order: the distance every reward and success flag uses.
double GoalDistance(const std::array<double, 3>& a, const std::array<double, 3>& b);

/// rotations.mat2euler of Gymnasium-Robotics for one row-major 3x3 matrix.
std::array<double, 3> Mat2Euler(const double* mat);

/// rotations.euler2quat of Gymnasium-Robotics: (w, x, y, z) of Euler angles (ex, ey, ez).
std::array<double, 4> Euler2Quat(const std::array<double, 3>& euler);

}  // namespace fetchscope
