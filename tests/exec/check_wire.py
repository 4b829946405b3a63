"""Checks what an exec: policy received (tests/exec/wire_dump.py's DUMP_DIR) against the Minari
pixel dataset of the same run and against `fetchscope render` PNGs (tests/exec_images_test.cc).

usage: check_wire.py DUMP_DIR DATASET_DIR RENDER_DIR STEPS FIELDS
RENDER_DIR holds NAME_tT.png for each camera NAME and step T in STEPS (comma list); FIELDS are the
--exec-fields given (comma list). Prints one line per failed check and exits 1, or "ok".
"""
import io
import json
import sys

import h5py
import numpy as np
from PIL import Image

dump, dataset, render_dir, steps, fields = sys.argv[1:6]
steps = [int(s) for s in steps.split(",")]
fields = fields.split(",")
failures = []
fail = failures.append

SLICES = {"grip_pos": (0, 3), "object_pos": (3, 6), "object_rel_pos": (6, 9)}
DTYPES = {"rgb": "uint8", "depth": "float32", "segmentation": "int32"}

meta = json.load(open(f"{dataset}/data/metadata.json"))
pixels = meta["pixels"]
H, W = pixels["height"], pixels["width"]
ep = h5py.File(f"{dataset}/data/main_data.hdf5", "r")["episode_0"]
obs = ep["observations"]
lines = [json.loads(l) for l in open(f"{dump}/lines.jsonl", "rb")]
T = len(obs["observation"])
if [m["t"] for m in lines] != list(range(T - 1)):
    fail(f"t of the lines: {[m['t'] for m in lines]}, expected 0..{T - 2}")

for m in lines:
    t = m["t"]
    want_keys = {"t", "cameras", "images", *fields} | ({"segmentation_legend"} if t == 0 else set())
    if set(m) != want_keys:
        fail(f"t={t}: keys {sorted(m)}, expected {sorted(want_keys)}")
    for f in fields:
        first, end = SLICES[f]
        if m.get(f) != obs["observation"][t][first:end].tolist():
            fail(f"t={t}: {f} {m.get(f)} is not the dataset's observation[{first}:{end}]")
    # the images in order: each camera, its layers in the order rgb, depth, segmentation
    want = [(c["name"], layer) for c in pixels["cameras"] for layer in pixels["layers"]]
    got = [(im["name"], im["layer"]) for im in m["images"]]
    if got != want:
        fail(f"t={t}: images {got}, expected {want}")
    for im in m["images"]:
        shape = [H, W, 3] if im["layer"] == "rgb" else [H, W]
        if im["shape"] != shape or im["dtype"] != DTYPES[im["layer"]]:
            fail(f"t={t}: {im['name']} {im['layer']}: {im['dtype']} {im['shape']}")
        if im["bytes"] != int(np.prod(shape)) * np.dtype(im["dtype"]).itemsize:
            fail(f"t={t}: {im['name']} {im['layer']}: {im['bytes']} bytes for shape {shape}")
        data = open(f"{dump}/t{t}_{im['name']}_{im['layer']}.bin", "rb").read()
        if len(data) != im["bytes"]:
            fail(f"t={t}: {im['name']} {im['layer']}: read {len(data)} of {im['bytes']} bytes")
            continue
        a = np.frombuffer(data, dtype="<" + np.dtype(im["dtype"]).str[1:]).reshape(shape)
        if im["layer"] == "rgb":
            stored = np.array(Image.open(io.BytesIO(obs["images"][im["name"]][t].tobytes())))
        else:
            stored = obs[im["layer"]][im["name"]][t]
        if not np.array_equal(a, stored):
            fail(f"t={t}: {im['name']} {im['layer']} differs from the dataset's image {t}")
        if im["layer"] == "rgb" and t in steps:
            rendered = np.array(Image.open(f"{render_dir}/{im['name']}_t{t}.png").convert("RGB"))
            if not np.array_equal(a, rendered):
                fail(f"t={t}: {im['name']} rgb differs from render in "
                     f"{int((a != rendered).any(-1).sum())} pixels")
    # each camera's intrinsics as stored, its pose as stored (per step for a moving camera)
    for c, stored in zip(m["cameras"], pixels["cameras"]):
        for k in ("name", "fovy", "fx", "fy", "cx", "cy"):
            if c[k] != stored[k]:
                fail(f"t={t}: camera {c['name']} {k} {c[k]}, stored {stored[k]}")
        pose = ep["infos"]["camera_pose"][c["name"]][t] if stored["moving"] else stored["pose"]
        if c["pose"] != list(np.asarray(pose, dtype=np.float64)):
            fail(f"t={t}: camera {c['name']} pose {c['pose']}, stored {list(pose)}")
    if t == 0 and m.get("segmentation_legend") != pixels["segmentation_legend"]:
        fail("t=0: the legend is not the dataset's")

for f in failures:
    print(f)
print("ok" if not failures else f"{len(failures)} failed")
sys.exit(1 if failures else 0)
