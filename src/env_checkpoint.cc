// FetchEnv's checkpoints (src/fetch_env.h: EnvCheckpoint): MuJoCo's state before the call that
// made the data, and that call repeated on restore. mj_step and mj_forward compute every derived
// value from this state alone (time, positions, velocities, activations, controls, the solver's
// warm start, the mocap targets and the applied forces), so repeating the call gives the same
// bits; tests/fetch_env_test.cc checks it against an env that never stopped.
#include <algorithm>

#include "base/errors.h"
#include "src/fetch_env.h"

namespace fetchscope {
namespace {

// Each array of the state, in EnvCheckpoint::sim's order: where it is in mjData and its length.
struct StateArray {
  mjtNum* values;
  int size;
};

std::array<StateArray, 10> StateArrays(const mjModel* m, mjData* d) {
  return {{{&d->time, 1},
           {d->qpos, m->nq},
           {d->qvel, m->nv},
           {d->act, m->na},
           {d->ctrl, m->nu},
           {d->qacc_warmstart, m->nv},
           {d->mocap_pos, 3 * m->nmocap},
           {d->mocap_quat, 4 * m->nmocap},
           {d->qfrc_applied, m->nv},
           {d->xfrc_applied, 6 * m->nbody}}};
}

}  // namespace

void FetchEnv::KeepCallState(bool step) {
  if (!checkpoints_) return;
  call_state_.clear();
  for (const StateArray& a : StateArrays(model_.get(), data_.get())) {
    call_state_.insert(call_state_.end(), a.values, a.values + a.size);
  }
  call_is_step_ = step;
}

EnvCheckpoint FetchEnv::Checkpoint() const {
  if (!has_reset_ || call_state_.empty()) {
    throw RunError(
        "no checkpoint: the environment keeps none before a reset made after "
        "EnableCheckpoints()");
  }
  EnvCheckpoint c;
  c.sim = call_state_;
  c.after_step = call_is_step_;
  c.goal = goal_;
  c.elapsed_steps = elapsed_steps_;
  c.rng = rng_;
  return c;
}

void FetchEnv::Restore(const EnvCheckpoint& c) {
  mjModel* m = model_.get();
  mjData* d = data_.get();
  const auto arrays = StateArrays(m, d);
  size_t size = 0;
  for (const StateArray& a : arrays) size += static_cast<size_t>(a.size);
  if (c.sim.size() != size) {
    throw RunError("checkpoint of " + std::to_string(c.sim.size()) + " numbers does not fit " +
                   spec_.id + "'s model (" + std::to_string(size) + ")");
  }
  const double* from = c.sim.data();
  for (const StateArray& a : arrays) {
    std::copy(from, from + a.size, a.values);
    from += a.size;
  }
  if (checkpoints_) {
    call_state_ = c.sim;
    call_is_step_ = c.after_step;
  }
  if (c.after_step) {
    mj_step(m, d);
    StepCallback();
  } else {
    mj_forward(m, d);
  }
  goal_ = c.goal;
  elapsed_steps_ = c.elapsed_steps;
  rng_ = c.rng;
  has_reset_ = true;
}

}  // namespace fetchscope
