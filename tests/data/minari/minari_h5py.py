#!/usr/bin/env python3
"""Minari 0.5 datasets with Debian's python3-h5py, for tests/minari_test.cc (Minari itself is not
installable here). Written from Minari 0.5.3's public source (minari/utils.py
create_dataset_from_buffers, data_collector/data_collector.py, dataset/minari_storage.py,
dataset/_storages/hdf5_storage.py, serialization.py) and gymnasium 1.x EnvSpec.to_json.

  minari_h5py.py write ROOT ID ENV_ID MODE OUT.json   MODE: buffers | collector | tiny
      write a dataset the way create_dataset_from_buffers (seeded episodes, one seed >= 2**63,
      no infos) or DataCollector with options={"minari_autoseed": False} (no seeds, an
      options/minari_autoseed attribute, an empty infos group, float32 sparse rewards, the
      episode statistics attributes) leave it; `tiny` is one short episode in small contiguous
      datasets (the fuzzer's seeds). OUT.json receives the values written.
  minari_h5py.py fuzz-seeds DIR
      the seed corpus of fuzz/fuzz_minari.cc: one-episode files in small compact datasets (under
      libFuzzer's 4096-byte -max_len), a wrong-length one, and a metadata.json.
  minari_h5py.py check ROOT ID EXPECTED.json
      check a dataset fetchscope wrote against Minari's format, as Minari 0.5.3's loader reads it.
"""
import json
import math
import os
import re
import sys

import h5py
import numpy as np

SUPPORTED = {"0.4.0", "0.4.1", "0.4.2", "0.4.3", "0.5.0", "0.5.1", "0.5.2", "0.5.3"}
ID_RE = re.compile(r"^(?:(?P<namespace>[-_\w][-_\w/]*[-_\w]+)\/)?(?:(?P<dataset>[-_\w]+?))"
                   r"(?:-v(?P<version>\d+))?$")
TASKS = {"Reach": "reach:MujocoFetchReachEnv", "Push": "push:MujocoFetchPushEnv",
         "PickAndPlace": "pick_and_place:MujocoFetchPickAndPlaceEnv",
         "Slide": "slide:MujocoFetchSlideEnv"}


def env_facts(env_id):
    m = re.fullmatch(r"Fetch(Reach|PickAndPlace|Push|Slide)(Dense)?-v4", env_id)
    assert m, env_id
    task, dense = m.group(1), bool(m.group(2))
    return task, dense, 10 if task == "Reach" else 25


def env_spec_json(env_id, max_episode_steps=50):
    # gymnasium 1.x: dataclasses.asdict(EnvSpec) less namespace/name/version, after make()
    task, dense, _ = env_facts(env_id)
    return json.dumps({
        "id": env_id, "entry_point": "gymnasium_robotics.envs.fetch." + TASKS[task],
        "reward_threshold": None, "nondeterministic": False,
        "max_episode_steps": max_episode_steps,
        "order_enforce": True, "disable_env_checker": False,
        "kwargs": {"reward_type": "dense" if dense else "sparse"},
        "additional_wrappers": [], "vector_entry_point": None})


def box(dtype, n, low, high):
    a = np.full((n,), low, dtype=dtype)
    b = np.full((n,), high, dtype=dtype)
    return {"type": "Box", "dtype": str(a.dtype), "shape": [n], "low": a.tolist(),
            "high": b.tolist()}


def spaces(env_id):
    # gymnasium's Dict sorts its keys; serialize_space writes type, dtype, shape, low, high
    _, _, width = env_facts(env_id)
    obs = {"type": "Dict", "subspaces": {
        "achieved_goal": box("float64", 3, -np.inf, np.inf),
        "desired_goal": box("float64", 3, -np.inf, np.inf),
        "observation": box("float64", width, -np.inf, np.inf)}}
    return json.dumps(obs), json.dumps(box("float32", 4, -1.0, 1.0))


def get_size(data_path):
    size = 0
    for dirpath, _, files in os.walk(data_path):
        for f in files:
            size += os.stat(os.path.join(dirpath, f)).st_size / 1000000
    return np.round(size, 1)


def update_metadata(data_path, new):
    path = os.path.join(data_path, "metadata.json")
    with open(path) as f:
        saved = json.load(f)
    saved.update(new)
    with open(path, "w") as f:
        json.dump(saved, f, default=lambda o: list(o) if isinstance(o, set) else None)


def make_episode(rng, env_id, steps, dense):
    _, _, width = env_facts(env_id)
    goal = rng.uniform(1.0, 1.5, size=3)
    obs = rng.normal(size=(steps + 1, width))
    achieved = rng.uniform(0.5, 1.5, size=(steps + 1, 3))
    d = np.linalg.norm(achieved[1:] - goal, axis=-1)
    rewards = -d if dense else -(d > 0.05).astype(np.float32)
    return {
        "observations": {"observation": obs, "achieved_goal": achieved,
                         "desired_goal": np.tile(goal, (steps + 1, 1))},
        "actions": rng.uniform(-1, 1, size=(steps, 4)).astype(np.float32),
        "rewards": list(rewards),
        "terminations": [False] * steps,
        "truncations": [False] * (steps - 1) + [True],
    }


def add_leaf(group, key, data, chunked=True):
    data = np.asarray(data)
    if chunked:  # hdf5_storage._add_episode_to_group: chunks=True, maxshape=(None, *shape)
        group.create_dataset(key, data=data, chunks=True, maxshape=(None, *data.shape[1:]))
    else:
        group.create_dataset(key, data=data)


def write(root, dataset_id, env_id, mode, out_path):
    task, dense, _ = env_facts(env_id)
    rng = np.random.default_rng(7)
    if mode == "tiny":
        lengths, seeds = [2], [3]
    elif mode == "buffers":
        lengths, seeds = [50, 7, 50], [0, 2**64 - 5, 123456789]
    else:
        lengths, seeds = [50, 50, 9], [None, None, None]
    episodes = [make_episode(rng, env_id, n, dense and mode != "collector") for n in lengths]

    namespace = ID_RE.fullmatch(dataset_id).group("namespace")
    dataset_dir = os.path.join(root, dataset_id)
    data_path = os.path.join(dataset_dir, "data")
    os.makedirs(data_path)
    parts = namespace.split("/") if namespace else []
    for i in range(len(parts)):  # create_namespace: {} in the namespace and its parents
        with open(os.path.join(root, *parts[: i + 1], "namespace_metadata.json"), "w") as f:
            json.dump({}, f)
    obs_space, act_space = spaces(env_id)
    with open(os.path.join(data_path, "metadata.json"), "w") as f:  # MinariStorage.new
        json.dump({"total_episodes": 0, "total_steps": 0, "data_format": "hdf5",
                   "observation_space": obs_space, "action_space": act_space,
                   "env_spec": env_spec_json(env_id)}, f)
    generated = {"dataset_id": dataset_id, "code_permalink": "https://example.org/collect.py",
                 "author": {"Jane Doe"}, "author_email": {"jane@example.org"},
                 "algorithm_name": "random", "description": "test dataset",
                 "minari_version": "0.5.3"}
    if mode != "collector":  # create_dataset_from_buffers updates the metadata first
        update_metadata(data_path, generated)
    file_path = os.path.join(data_path, "main_data.hdf5")
    total_steps = 0
    with h5py.File(file_path, "a", track_order=True) as f:
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
                add_leaf(obs, k, ep["observations"][k], mode != "tiny")
            for k in ("actions", "rewards", "terminations", "truncations"):
                add_leaf(g, k, ep[k], mode != "tiny")
            if mode == "collector":
                g.create_group("infos")  # record_infos=False leaves {} behind
                r = np.asarray(ep["rewards"])
                g.attrs.update({"rewards_sum": float(r.sum()), "rewards_mean": float(r.mean()),
                                "rewards_std": float(r.std()), "rewards_max": float(r.max()),
                                "rewards_min": float(r.min())})
    update_metadata(data_path, {"total_steps": total_steps, "total_episodes": len(episodes),
                                "dataset_size": get_size(data_path)})
    if mode == "collector":
        update_metadata(data_path, generated)
    with open(out_path, "w") as f:
        json.dump({"episodes": [{
            "seed": seed,
            "observation": ep["observations"]["observation"].tolist(),
            "achieved_goal": ep["observations"]["achieved_goal"].tolist(),
            "desired_goal": ep["observations"]["desired_goal"].tolist(),
            "actions": ep["actions"].astype(np.float64).tolist(),
            "rewards": [float(r) for r in ep["rewards"]],
            "reward_dtype": str(np.asarray(ep["rewards"]).dtype),
            "truncations": ep["truncations"]} for ep, seed in zip(episodes, seeds)]}, f)


def check(root, dataset_id, expected_path):
    with open(expected_path) as f:
        want = json.load(f)
    env_id = want["env_id"]
    dataset_dir = os.path.join(root, dataset_id)
    data_path = os.path.join(dataset_dir, "data")
    assert sorted(os.listdir(dataset_dir)) == ["data"], os.listdir(dataset_dir)
    assert sorted(os.listdir(data_path)) == ["main_data.hdf5", "metadata.json"]
    # no temporary folders left beside it; every namespace has its (empty) metadata
    namespace = ID_RE.fullmatch(dataset_id).group("namespace")
    assert ID_RE.fullmatch(dataset_id).group("version") is not None
    parent = os.path.dirname(dataset_dir)
    assert not [n for n in os.listdir(parent) if n.startswith(".")], os.listdir(parent)
    parts = namespace.split("/")
    for i in range(len(parts)):
        with open(os.path.join(root, *parts[: i + 1], "namespace_metadata.json")) as f:
            assert json.load(f) == {}
    raw = open(os.path.join(data_path, "metadata.json")).read()
    meta = json.loads(raw)
    # MinariStorage.new's keys, then _generate_dataset_metadata's (author_email where given,
    # requirements), then update_episodes' dataset_size
    keys = ["total_episodes", "total_steps", "data_format", "observation_space", "action_space",
            "env_spec", "dataset_id", "code_permalink", "author"]
    keys += ["author_email"] if want.get("author_email") else []
    keys += ["algorithm_name", "description", "minari_version", "requirements", "dataset_size"]
    assert list(meta) == keys, list(meta)
    assert meta["dataset_id"] == dataset_id
    assert meta["minari_version"] in SUPPORTED
    assert meta["data_format"] == "hdf5"
    assert meta["author"] == [want.get("author", "fetchscope")], meta["author"]
    if want.get("author_email"):
        assert meta["author_email"] == [want["author_email"]], meta["author_email"]
    assert meta["requirements"] == ["gymnasium_robotics==1.4.2", "mujoco==2.2.2"], meta
    # what recover_environment() parses with packaging's Requirement
    for req in meta["requirements"]:
        assert re.fullmatch(r"[A-Za-z0-9_.-]+==[0-9.]+", req), req
    assert meta["algorithm_name"] == want["algorithm_name"]
    assert isinstance(meta["code_permalink"], str)
    obs_space, act_space = spaces(env_id)
    assert meta["observation_space"] == obs_space, meta["observation_space"]
    assert meta["action_space"] == act_space, meta["action_space"]
    assert "-Infinity" in meta["observation_space"] and "null" not in meta["observation_space"]
    steps = want.get("max_episode_steps", 50)
    assert meta["env_spec"] == env_spec_json(env_id, steps), meta["env_spec"]
    spec = json.loads(meta["env_spec"].replace('"order_enforce": true,', ""))
    assert spec["id"] == env_id and spec["max_episode_steps"] == steps
    # json.dump's own spacing, so the file is what Python would have written
    assert raw == json.dumps(meta), "metadata.json is not json.dump's output"
    assert meta["dataset_size"] == get_size(data_path), (meta["dataset_size"], get_size(data_path))
    episodes = want["episodes"]
    assert meta["total_episodes"] == len(episodes)
    with h5py.File(os.path.join(data_path, "main_data.hdf5"), "r") as f:
        assert f['/'].id.get_create_plist().get_link_creation_order() != 0  # track_order=True
        assert list(f.keys()) == [f"episode_{i}" for i in range(len(episodes))]
        total = 0
        for i, ep in enumerate(episodes):
            g = f[f"episode_{i}"]
            t = len(ep["rewards"])
            total += t
            assert g.attrs["id"] == i and g.attrs["id"].dtype == np.int64
            assert g.attrs["total_steps"] == t and g.attrs["total_steps"].dtype == np.int64
            if ep["seed"] is None:
                assert "seed" not in g.attrs
            else:
                s = g.attrs["seed"]
                assert int(s) == ep["seed"], (int(s), ep["seed"])
                assert s.dtype == (np.int64 if ep["seed"] < 2**63 else np.uint64), s.dtype
            assert sorted(g.keys()) == ["actions", "infos", "observations", "rewards",
                                        "terminations", "truncations"], list(g.keys())
            assert sorted(g["observations"].keys()) == ["achieved_goal", "desired_goal",
                                                        "observation"]
            _, _, width = env_facts(env_id)
            for k, n, dt in [("observations/observation", width, np.float64),
                             ("observations/achieved_goal", 3, np.float64),
                             ("observations/desired_goal", 3, np.float64),
                             ("actions", 4, np.float32)]:
                d = g[k]
                rows = t if k == "actions" else t + 1
                assert d.dtype == dt and d.shape == (rows, n), (k, d.dtype, d.shape)
                assert d.maxshape == (None, n) and d.chunks is not None, (k, d.maxshape)
                assert np.array_equal(d[()], np.asarray(ep[k.split("/")[-1]], dtype=dt)), k
            # Gymnasium-Robotics' reward dtypes: float32 for the sparse ids, float64 dense
            reward_dt = np.float64 if env_facts(env_id)[1] else np.float32
            for k, dt in [("rewards", reward_dt), ("terminations", np.bool_),
                          ("truncations", np.bool_)]:
                d = g[k]
                assert d.dtype == dt and d.shape == (t,) and d.maxshape == (None,), (k, d.dtype)
            assert np.array_equal(g["rewards"][()], np.asarray(ep["rewards"]))
            assert not g["terminations"][()].any()
            assert g["truncations"][()].tolist() == ep["truncations"]
            s = g["infos/is_success"]
            assert s.dtype == np.float32 and s.shape == (t + 1,)
            assert s[()].tolist() == ep["is_success"]
        assert meta["total_steps"] == total
    print("ok")


def compact(group, name, data):
    data = np.asarray(data)
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    dcpl.set_layout(h5py.h5d.COMPACT)
    dset = h5py.h5d.create(group.id, name.encode(), h5py.h5t.py_create(data.dtype, logical=True),
                           h5py.h5s.create_simple(data.shape), dcpl=dcpl)
    dset.write(h5py.h5s.ALL, h5py.h5s.ALL, data)


def fuzz_seeds(folder):
    os.makedirs(folder, exist_ok=True)
    rng = np.random.default_rng(11)
    for name, width, seed, reward, action_rows, with_success in [
            ("reach_seeded.hdf5", 10, 2**64 - 1, np.float64, 1, True),
            ("push_unseeded.hdf5", 25, None, np.float32, 1, False),
            ("wrong_length.hdf5", 10, 5, np.float64, 2, False)]:
        with h5py.File(os.path.join(folder, name), "w", track_order=True, libver="latest") as f:
            g = f.create_group("episode_0")
            g.attrs["id"] = 0
            if seed is not None:
                g.attrs["seed"] = seed
            g.attrs["total_steps"] = 1
            obs = g.create_group("observations")
            compact(obs, "observation", rng.normal(size=(2, width)))
            compact(obs, "achieved_goal", rng.normal(size=(2, 3)))
            compact(obs, "desired_goal", rng.normal(size=(2, 3)))
            compact(g, "actions", rng.uniform(-1, 1, size=(action_rows, 4)).astype(np.float32))
            compact(g, "rewards", np.array([-1], dtype=reward))
            compact(g, "terminations", np.zeros(1, dtype=bool))
            compact(g, "truncations", np.ones(1, dtype=bool))
            infos = g.create_group("infos")
            if with_success:
                compact(infos, "is_success", np.array([0, 1], dtype=np.float32))
    obs_space, act_space = spaces("FetchPush-v4")
    with open(os.path.join(folder, "metadata.json"), "w") as f:
        json.dump({"total_episodes": 1, "total_steps": 1, "data_format": "hdf5",
                   "observation_space": obs_space, "action_space": act_space,
                   "env_spec": env_spec_json("FetchPush-v4"), "dataset_id": "fuzz/seed-v0",
                   "minari_version": "0.5.3", "dataset_size": 0.0}, f)


if __name__ == "__main__":
    if sys.argv[1] == "write":
        write(*sys.argv[2:7])
    elif sys.argv[1] == "fuzz-seeds":
        fuzz_seeds(sys.argv[2])
    elif sys.argv[1] == "check":
        check(*sys.argv[2:5])
    else:
        sys.exit("usage: minari_h5py.py write|fuzz-seeds|check ...")
