#!/usr/bin/env python3
"""Minari 0.5 datasets of real Fetch episodes, for tests/cli_record_from_dataset_test.cc: the episodes of
fetchscope rollouts (the genuine env's numbers) written with Debian's python3-h5py in exactly the
layout Minari 0.5's create_dataset_from_buffers or DataCollector leaves (the layout helpers are
minari_h5py.py's, written from Minari 0.5.3's public source).

  minari_in_h5py.py ROOT ID buffers TRAJ.json [TRAJ.json ...]
      create_dataset_from_buffers: episode i is the first episode of the i-th file, with that
      file's seed as its `seed` attribute (a 64-bit int, as DataCollector's autoseed draws them).
  minari_in_h5py.py ROOT ID collector TRAJ.json
      DataCollector with options={"minari_autoseed": False}: the file's episodes, no seeds (the
      episodes after the first continued the generator), an empty infos group.

Actions are float32 (the action space's dtype); rewards float32 for the sparse ids and float64
for the dense ones, as the env returns them.
"""
import json
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from minari_h5py import (ID_RE, add_leaf, env_facts, env_spec_json, get_size,  # noqa: E402
                         spaces, update_metadata)


def episode_of(trajectory_episode, dense):
    steps = trajectory_episode["steps"]
    obs = {k: np.array([s[k] for s in steps], dtype=np.float64)
           for k in ("observation", "achieved_goal", "desired_goal")}
    rewards = np.array([s["reward"] for s in steps[1:]], dtype=np.float64 if dense else np.float32)
    n = len(steps) - 1
    return {"observations": obs,
            "actions": np.array([s["action"] for s in steps[1:]], dtype=np.float32),
            "rewards": rewards,
            "terminations": np.zeros(n, dtype=bool),
            "truncations": np.array([False] * (n - 1) + [True])}


def main(root, dataset_id, mode, files):
    loaded = [json.load(open(f)) for f in files]
    env_id = loaded[0]["env_id"]
    _, dense, _ = env_facts(env_id)
    if mode == "buffers":
        episodes = [episode_of(t["episodes"][0], dense) for t in loaded]
        seeds = [int(t["seed"]) for t in loaded]
    else:
        episodes = [episode_of(e, dense) for e in loaded[0]["episodes"]]
        seeds = [None] * len(episodes)
    namespace = ID_RE.fullmatch(dataset_id).group("namespace")
    data_path = os.path.join(root, dataset_id, "data")
    os.makedirs(data_path)
    parts = namespace.split("/") if namespace else []
    for i in range(len(parts)):  # create_namespace
        with open(os.path.join(root, *parts[: i + 1], "namespace_metadata.json"), "w") as f:
            json.dump({}, f)
    obs_space, act_space = spaces(env_id)
    with open(os.path.join(data_path, "metadata.json"), "w") as f:  # MinariStorage.new
        json.dump({"total_episodes": 0, "total_steps": 0, "data_format": "hdf5",
                   "observation_space": obs_space, "action_space": act_space,
                   "env_spec": env_spec_json(env_id)}, f)
    generated = {"dataset_id": dataset_id, "code_permalink": "https://example.org/collect.py",
                 "author": {"Jane Doe"}, "author_email": {"jane@example.org"},
                 "algorithm_name": "random", "description": "Fetch episodes",
                 "minari_version": "0.5.3"}
    if mode == "buffers":
        update_metadata(data_path, generated)
    total_steps = 0
    with h5py.File(os.path.join(data_path, "main_data.hdf5"), "a", track_order=True) as f:
        for i, (ep, seed) in enumerate(zip(episodes, seeds)):
            g = f.create_group(f"episode_{i}")
            g.attrs["id"] = i
            if seed is not None:
                g.attrs["seed"] = seed
            if mode == "collector":
                g.attrs.update({"options/minari_autoseed": False})
            g.attrs["total_steps"] = len(ep["rewards"])
            total_steps += len(ep["rewards"])
            obs = g.create_group("observations")
            for k in ("observation", "achieved_goal", "desired_goal"):
                add_leaf(obs, k, ep["observations"][k])
            for k in ("actions", "rewards", "terminations", "truncations"):
                add_leaf(g, k, ep[k])
            if mode == "collector":
                g.create_group("infos")
                r = ep["rewards"]
                g.attrs.update({"rewards_sum": float(r.sum()), "rewards_mean": float(r.mean()),
                                "rewards_std": float(r.std()), "rewards_max": float(r.max()),
                                "rewards_min": float(r.min())})
    update_metadata(data_path, {"total_steps": total_steps, "total_episodes": len(episodes),
                                "dataset_size": get_size(data_path)})
    if mode == "collector":
        update_metadata(data_path, generated)


if __name__ == "__main__":
    if len(sys.argv) < 5 or sys.argv[3] not in ("buffers", "collector"):
        sys.exit("usage: minari_in_h5py.py ROOT ID buffers|collector TRAJ.json ...")
    main(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:])
