#!/usr/bin/env python3
"""An exec: policy for tests: notes its pid, process group and LD_LIBRARY_PATH in
$FETCHSCOPE_TEST_PID_DIR/<pid>.json, then moves towards the goal a little each step."""
import json
import os
import sys

pid_dir = os.environ.get("FETCHSCOPE_TEST_PID_DIR")
if pid_dir:
    info = {"pid": os.getpid(), "pgid": os.getpgid(0),
            "ld_library_path": os.environ.get("LD_LIBRARY_PATH")}
    tmp = os.path.join(pid_dir, ".%d.tmp" % os.getpid())
    with open(tmp, "w") as f:
        json.dump(info, f)
    os.rename(tmp, os.path.join(pid_dir, "%d.json" % os.getpid()))

for line in sys.stdin:
    msg = json.loads(line)
    grip = msg["observation"][:3]
    goal = msg["desired_goal"]
    action = [max(-1.0, min(1.0, 10.0 * (g - p))) for g, p in zip(goal, grip)] + [0.0]
    print(" ".join(repr(a) for a in action), flush=True)
