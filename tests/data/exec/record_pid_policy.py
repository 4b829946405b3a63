#!/usr/bin/env python3
"""An exec: policy for tests: at its first step notes its pid, process group and
LD_LIBRARY_PATH in $FETCHSCOPE_TEST_PID_DIR/<pid>.json; moves towards the goal each step."""
import json
import os
import sys


def note_self():
    pid_dir = os.environ.get("FETCHSCOPE_TEST_PID_DIR")
    if not pid_dir:
        return
    info = {"pid": os.getpid(), "pgid": os.getpgid(0),
            "ld_library_path": os.environ.get("LD_LIBRARY_PATH")}
    tmp = os.path.join(pid_dir, ".%d.tmp" % os.getpid())
    with open(tmp, "w") as f:
        json.dump(info, f)
    os.rename(tmp, os.path.join(pid_dir, "%d.json" % os.getpid()))


first = True
for line in sys.stdin:
    if first:  # noted once the first episode has started
        note_self()
        first = False
    msg = json.loads(line)
    grip = msg["observation"][:3]
    goal = msg["desired_goal"]
    action = [max(-1.0, min(1.0, 10.0 * (g - p))) for g, p in zip(goal, grip)] + [0.0]
    print(" ".join(repr(a) for a in action), flush=True)
