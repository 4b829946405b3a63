#!/usr/bin/python3
"""Writes the numpy test vectors that tests/rng_test.cc and tests/replay_file_test.cc compare against.

Regenerate (from the repository root, with Debian's python3-numpy, no PyPI needed):

    /usr/bin/python3 tools/make_rng_vectors.py

It rewrites tests/data/rng_vectors.json (generator vectors, plus Python repr() texts of
doubles for tests/json_util_test.cc) and the sample replay files in tests/data/replay/
(replay.csv, replay.jsonl, replay_f32.npy, replay_f64.npy). The output is deterministic, so a
regenerated file only differs from the committed one if numpy's generator changed.

Doubles are stored as repr() strings (shortest round-trip) and as their IEEE-754 bit patterns
in hex, so the C++ side can compare bit for bit without trusting any JSON number parser.
"""

import json
import os
import struct

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SEEDS = [0, 1, 42, 123, 2**32 + 7, 2**63 + 5, 2**64 - 1]


def double_bits(x):
    return "%016x" % struct.unpack("<Q", struct.pack("<d", float(x)))[0]


def float_bits(x):
    return "%08x" % struct.unpack("<I", struct.pack("<f", np.float32(x)))[0]


def doubles(values):
    return [{"repr": repr(float(v)), "bits": double_bits(v)} for v in values]


def vectors_for(seed):
    def gen():
        return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed)))

    g = gen()
    uint64 = ["%016x" % int(v) for v in g.bit_generator.random_raw(20)]

    g = gen()
    next_double = doubles(g.random() for _ in range(20))

    g = gen()
    uniform = doubles(g.uniform(-0.15, 0.15, size=10))

    # gymnasium Box(-1, 1, (4,), float32).sample() on the same kind of generator.
    g = gen()
    box = []
    for _ in range(5):
        sample = g.uniform(low=-1.0, high=1.0, size=4).astype(np.float32)
        box.append([{"repr": repr(float(v)), "bits": float_bits(v)} for v in sample])

    return {
        "seed": str(seed),  # a string: 2**64-1 does not fit every JSON reader's integers
        "next_uint64": uint64,
        "next_double": next_double,
        "uniform_m015_015": uniform,
        "box_sample_f32": box,
    }


def python_float_reprs():
    """Doubles of every kind with Python's repr(), which json.dumps also uses: the C++ JSON
    writer (src/json_util.cc FormatDouble) must produce the same text."""
    values = [0.0, -0.0, 1.0, -1.0, 0.1, 1 / 3, 123.0, 1e15, 1e16, 9999999999999998.0, 0.0001,
              0.00001, 1e-4 * 0.99, 5e-324, -5e-324, 2.2250738585072014e-308,
              2.225073858507201e-308, 1.7976931348623157e308, -1.7976931348623157e308,
              4.1752050594835e+78, 1e22, 1e21, 1e-7, 2**53, 2**53 + 2.0, -0.05, 0.05]
    g = np.random.Generator(np.random.PCG64(np.random.SeedSequence(2024)))
    raw = g.bit_generator.random_raw(600)
    for i, bits in enumerate(raw):
        bits = int(bits)
        if i % 3 == 1:
            bits &= 0x800FFFFFFFFFFFFF  # subnormal
        v = struct.unpack("<d", struct.pack("<Q", bits))[0]
        if np.isfinite(v):
            values.append(v)
    # ordinary magnitudes around the fixed/scientific switch points
    for k in range(-8, 20):
        values.extend(float(u) * 10.0**k for u in g.uniform(-1, 1, size=4))
    return [{"bits": double_bits(v), "repr": repr(float(v))} for v in values]


def write_rng_vectors():
    data = {
        "generator": "numpy.random.Generator(PCG64(SeedSequence(seed)))",
        "numpy_version": np.__version__,
        "seeds": [vectors_for(s) for s in SEEDS],
        "python_float_repr": python_float_reprs(),
    }
    path = os.path.join(ROOT, "tests", "data", "rng_vectors.json")
    with open(path, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


def write_replay_samples():
    folder = os.path.join(ROOT, "tests", "data", "replay")
    os.makedirs(folder, exist_ok=True)
    g = np.random.Generator(np.random.PCG64(np.random.SeedSequence(7)))
    actions = g.uniform(-1.0, 1.0, size=(6, 4))
    # one out-of-range row: the env clips, the reader must not
    actions[5] = [1.5, -2.0, 0.0, 1.0]
    np.save(os.path.join(folder, "replay_f64.npy"), actions.astype("<f8"))
    np.save(os.path.join(folder, "replay_f32.npy"), actions.astype("<f4"))
    with open(os.path.join(folder, "replay.csv"), "w") as f:
        f.write("dx,dy,dz,gripper\n")
        for row in actions:
            f.write(",".join(repr(float(v)) for v in row) + "\n")
    with open(os.path.join(folder, "replay.jsonl"), "w") as f:
        for i, row in enumerate(actions):
            values = [float(v) for v in row]
            # both accepted line forms
            f.write(json.dumps({"action": values} if i % 2 else values) + "\n")


if __name__ == "__main__":
    write_rng_vectors()
    write_replay_samples()
