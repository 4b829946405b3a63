#!/usr/bin/env python3
"""A FetchReach policy that finds the goal in camera images: numpy only, served over fetchscope's
JSON-lines protocol with images on the wire (docs/guide/your-policy.md).

    fetchscope record --env-id FetchReach-v4 --policy "exec:python3 pixel_reach.py" \
        --obs-camera front=external_camera_0 \
        --obs-camera side=free:lookat=1.34,0.75,0.53,distance=1.0,azimuth=-90,elevation=-35 \
        --obs-layers rgb,depth,segmentation --obs-size 96x80 --exec-fields grip_pos \
        --episodes 50 --out out/pixel-reach

It needs the depth and segmentation layers (rgb is only for the CNN sketch below) and uses
nothing of the state but grip_pos; python3 must have numpy (Debian: python3-numpy). Each step
it takes the pixels of the goal marker (site target0, a sphere of radius 0.02 m) from every
camera's segmentation, back-projects them with the depth, the intrinsics and the camera's pose
to points in the world, and fits one sphere of that radius through them all. The gripper hides
the marker as it gets close, so the estimate is kept from the frame that saw the most of it.
The legend names the marker by its site (its entry also names the body the site is on).
Two cameras, because the arm hides some goals from any single view. A target never seen gives
zero actions, said on stderr. stdout carries the actions and nothing else: log to stderr.
"""
import json
import sys

import numpy as np

RADIUS = 0.02  # target0's sphere, metres
GAIN = 1.0     # action = GAIN * (goal - grip) / 0.05 m, clipped to [-1, 1]


def rotation(q):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def target_points(cam, depth, seg, target_id):
    """World points of the target's pixels in one camera, and the camera's position."""
    v, u = np.nonzero((seg == target_id) & (depth > 0))
    d = depth[v, u].astype(np.float64)
    # MuJoCo's camera frame: x right, y up, looking along -z; image v grows downwards
    local = np.stack([(u - cam["cx"]) / cam["fx"] * d, -(v - cam["cy"]) / cam["fy"] * d, -d], 1)
    pose = np.asarray(cam["pose"], dtype=np.float64)
    return local @ rotation(pose[3:]).T + pose[:3], pose[:3]


def fit_sphere(views, iterations=10, prior=0.1):
    """Centre c of the sphere of radius RADIUS through the points of every view: Gauss-Newton on
    |X - c| = RADIUS. The first guess is the best view's mean point pushed 2/3 of the radius
    along its viewing ray (the mean depth of a sphere's visible half); a weak pull towards it
    keeps the fit well posed when only a pixel or two are seen."""
    points, eye = max(views, key=lambda view: len(view[0]))
    mean = points.mean(0)
    c0 = mean + 2 / 3 * RADIUS * (mean - eye) / np.linalg.norm(mean - eye)
    X, c = np.concatenate([p for p, _ in views]), c0.copy()
    for _ in range(iterations):
        D = X - c
        n = np.linalg.norm(D, axis=1)
        J = D / n[:, None]  # minus the Jacobian of the residuals n - RADIUS
        c = c + np.linalg.solve(J.T @ J + prior * np.eye(3), J.T @ (n - RADIUS) + prior * (c0 - c))
    return c


def read_step(stream):
    """One step: the JSON line, then the raw bytes of each image it lists, in order."""
    line = stream.readline()
    if not line:
        return None, None
    msg = json.loads(line)
    images = {}
    for entry in msg.get("images", []):
        buf = stream.read(entry["bytes"])
        if len(buf) != entry["bytes"]:
            raise EOFError(f"pixel_reach: {len(buf)} of {entry['bytes']} image bytes")
        dtype = np.dtype(entry["dtype"]).newbyteorder("<")
        images[entry["name"], entry["layer"]] = np.frombuffer(buf, dtype).reshape(entry["shape"])
    return msg, images


def main():
    print("pixel_reach: serving", file=sys.stderr)
    target_id, goal, seen = None, None, 0
    while True:
        msg, images = read_step(sys.stdin.buffer)
        if msg is None:
            break
        t = msg["t"]
        if t == 0:  # a new episode: a new goal
            if goal is None and target_id is not None:
                print("pixel_reach: the last episode never saw its target", file=sys.stderr)
            legend = msg.get("segmentation_legend")
            if legend is None or "cameras" not in msg:
                sys.exit("pixel_reach: no cameras or segmentation legend on the wire: run with "
                         "--obs-camera ... --obs-layers depth,segmentation")
            target_id = next(e["id"] for e in legend if e.get("site") == "target0")
            goal, seen = None, 0
        views = []
        for cam in msg["cameras"]:
            depth, seg = images[cam["name"], "depth"], images[cam["name"], "segmentation"]
            points, eye = target_points(cam, depth, seg, target_id)
            if len(points):
                views.append((points, eye))
        # A learned policy would go here instead of the geometry, e.g. a PyTorch CNN:
        #   x = torch.from_numpy(np.stack([images[c["name"], "rgb"] for c in msg["cameras"]]))
        #   x = x.permute(0, 3, 1, 2).float().div(255).flatten(0, 1)[None]  # (1, 3*cams, H, W)
        #   with torch.no_grad():
        #       action = net(x, torch.tensor([msg["grip_pos"]])).squeeze(0).numpy()
        pixels = sum(len(p) for p, _ in views)
        if pixels > seen:  # the fullest view of the target so far
            goal, seen = fit_sphere(views), pixels
        action = np.zeros(4)
        if goal is not None:
            grip = np.asarray(msg["grip_pos"], dtype=np.float64)
            action[:3] = np.clip(GAIN * (goal - grip) / 0.05, -1.0, 1.0)
        print(json.dumps(action.tolist()), flush=True)
    if goal is None and target_id is not None:
        print("pixel_reach: the last episode never saw its target", file=sys.stderr)


if __name__ == "__main__":
    main()
