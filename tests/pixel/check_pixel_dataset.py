"""Checks a pixel Minari dataset against `fetchscope render` PNGs (tests/pixel_dataset_test.cc).

usage: check_pixel_dataset.py DATASET_DIR RENDER_DIR STEPS OBJECT_BODY [PLAIN_DATASET_DIR]
RENDER_DIR holds CAM_tT.png, CAM_tT_depth.png, CAM_tT_segmentation.png and
CAM_tT_segmentation_legend.json for each camera name CAM and step T in STEPS (comma list).
Prints one line per failed check and exits 1, or prints "ok" and exits 0.
"""
import io
import json
import sys

import h5py
import numpy as np
from PIL import Image

dataset, render_dir, steps, object_body = sys.argv[1:5]
plain = sys.argv[5] if len(sys.argv) > 5 else None
steps = [int(s) for s in steps.split(",")]
failures = []


def fail(msg):
    failures.append(msg)


meta = json.load(open(f"{dataset}/data/metadata.json"))
pixels = meta["pixels"]
legend = {e["id"]: (e["body"], e["site"]) for e in pixels["segmentation_legend"]}
space = json.loads(meta["observation_space"].replace("-Infinity", "-1e999").replace("Infinity", "1e999"))
for key in ("achieved_goal", "depth", "desired_goal", "images", "observation", "segmentation"):
    if key not in space["subspaces"]:
        fail(f"observation_space has no {key}")
f = h5py.File(f"{dataset}/data/main_data.hdf5", "r")
ep = f["episode_0"]
obs = ep["observations"]
object_id = [i for i, (b, s) in legend.items() if b == object_body and s is None][0]

for cam in pixels["cameras"]:
    name = cam["name"]
    K = np.array(cam["K"])
    rgb_space = space["subspaces"]["images"]["subspaces"][name]
    if rgb_space["dtype"] != "uint8" or rgb_space["shape"] != [pixels["height"], pixels["width"], 3]:
        fail(f"{name}: rgb space {rgb_space['dtype']} {rgb_space['shape']}")
    for t in steps:
        base = f"{render_dir}/{name}_t{t}"
        want = np.array(Image.open(base + ".png").convert("RGB"))
        got = np.array(Image.open(io.BytesIO(obs["images"][name][t].tobytes())))
        if got.shape != want.shape or not np.array_equal(got, want):
            fail(f"{name} t={t}: rgb differs from render in {int((got != want).any(-1).sum())} pixels")
        mm = np.array(Image.open(base + "_depth.png")).astype(np.int64)
        d = obs["depth"][name][t]
        if d.dtype != np.float32:
            fail(f"{name}: depth dtype {d.dtype}")
        hit = mm > 0  # render's millimetres stop at 65.535 m (0 beyond)
        if not np.array_equal(hit, (d > 0) & (d <= 65.5355)):
            fail(f"{name} t={t}: depth has hits where render has none")
        err = np.abs(d[hit].astype(np.float64) * 1000 - mm[hit])
        if err.size and err.max() > 1.0:
            fail(f"{name} t={t}: depth differs from render by {err.max():.3f} mm")
        seg = obs["segmentation"][name][t]
        colours = json.load(open(base + "_segmentation_legend.json"))
        objects = colours["objects"] if isinstance(colours, dict) and "objects" in colours else colours
        by_colour = {tuple(o["rgb"]): (o["body"], o["site"]) for o in objects}
        seg_png = np.array(Image.open(base + "_segmentation.png").convert("RGB"))
        mismatched = 0
        for (y, x) in np.ndindex(seg.shape):
            want_obj = by_colour.get(tuple(seg_png[y, x]))
            got_obj = legend.get(int(seg[y, x]))
            if want_obj != got_obj:
                mismatched += 1
        if mismatched:
            fail(f"{name} t={t}: segmentation names another object than render in {mismatched} pixels")
        # the intrinsics and pose project the object onto its own pixels
        pose = np.array(cam["pose"]) if not cam["moving"] else ep["infos"]["camera_pose"][name][t]
        pos, q = pose[:3], pose[3:]
        w, x, y, z = q
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        p_cam = R.T @ (obs["achieved_goal"][t] - pos)
        p_cv = np.array([p_cam[0], -p_cam[1], -p_cam[2]])  # OpenCV: x right, y down, z forward
        if p_cv[2] <= 0:
            continue
        u, v, _ = K @ (p_cv / p_cv[2])
        ui, vi = int(round(u)), int(round(v))
        if not (0 <= ui < seg.shape[1] and 0 <= vi < seg.shape[0]):
            continue
        window = seg[max(0, vi - 1):vi + 2, max(0, ui - 1):ui + 2]
        z = float(d[vi, ui])
        if object_id not in window:
            # only something nearer than the object may hide it (the arm above it)
            if not (0 < z < p_cv[2] - 0.02):
                fail(f"{name} t={t}: the object projects to ({u:.1f}, {v:.1f}), which shows "
                     f"{sorted(set(window.flatten().tolist()))} at {z:.3f} m, not the object "
                     f"{object_id} at {p_cv[2]:.3f} m")
            continue
        if seg[vi, ui] != object_id:
            continue
        # the pixel's depth, back-projected, lands on the object (a 5 cm cube)
        back = np.array([(ui - K[0, 2]) / K[0, 0] * z, (vi - K[1, 2]) / K[1, 1] * z, z])
        world = pos + R @ np.array([back[0], -back[1], -back[2]])
        miss = np.linalg.norm(world - obs["achieved_goal"][t])
        if miss > 0.045:
            fail(f"{name} t={t}: the object's pixel back-projects {miss:.3f} m from its centre")

if plain:
    g = h5py.File(f"{plain}/data/main_data.hdf5", "r")
    for e in g:
        for key in ("actions", "rewards", "terminations", "truncations", "infos/is_success",
                    "observations/observation", "observations/achieved_goal",
                    "observations/desired_goal"):
            a, b = g[e][key][()], f[e][key][()]
            if a.dtype != b.dtype or a.shape != b.shape or a.tobytes() != b.tobytes():
                fail(f"{e}/{key} differs from the dataset without images")
        if dict(g[e].attrs) != dict(f[e].attrs):
            fail(f"{e}: attributes differ from the dataset without images")

for line in failures:
    print(line)
print("ok" if not failures else f"{len(failures)} check(s) failed")
sys.exit(1 if failures else 0)
