#!/usr/bin/env python3
"""CPU per recorded frame of two fetchscope binaries, side by side in one run.

  tools/cpu-per-frame.py OLD_BINARY NEW_BINARY [ROUNDS]

Each round records FetchPush-v4, 4 episodes of 50 steps (480x480, HUD, MP4 + sheet + JSON), with
each binary, alternating which goes first, and reads the run's own CPU account
(manifest.json's timings_s.cpu_ms_per_frame: thread CPU clocks per stage). Prints the median of
each stage and NEW/OLD. CPU time is steady on a busy machine where wall time is not."""
import json, os, statistics, subprocess, sys, tempfile

old, new = sys.argv[1], sys.argv[2]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 6
runs = {old: [], new: []}
with tempfile.TemporaryDirectory() as tmp:
    for r in range(rounds):
        for binary in (old, new) if r % 2 == 0 else (new, old):
            out = os.path.join(tmp, f"run{r}-{'old' if binary == old else 'new'}")
            subprocess.run([binary, "record", "--env-id", "FetchPush-v4", "--episodes", "4",
                            "--steps", "50", "--out", out, "--quiet", "--no-report"], check=True)
            with open(os.path.join(out, "manifest.json")) as f:
                runs[binary].append(json.load(f)["timings_s"]["cpu_ms_per_frame"])
print(f"{'stage':12s} {'old ms':>8s} {'new ms':>8s} {'new/old':>8s}   ({rounds} runs each)")
for stage in ("outside_gl", "process", "sim", "scene", "hud", "copy", "convert", "encode", "sheet"):
    a = statistics.median(run[stage] for run in runs[old])
    b = statistics.median(run[stage] for run in runs[new])
    print(f"{stage:12s} {a:8.3f} {b:8.3f} {b / a:8.3f}")
