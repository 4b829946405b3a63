#!/usr/bin/env bash
# How fast a large run's report opens (BENCHMARKS.md, "Report and episode viewer"): records a
# small run (FetchPush-v4, scripted, SEED_EPISODES episodes of 50 steps at 64x64), copies its
# episodes into a run of EPISODES episodes (each copy's files and manifest entry under its new
# index: the page cannot tell), writes that run's report with `fetchscope report` (timed), and
# opens it RUNS times in headless Chromium (web/test/measure_open.mjs): the time until the page
# has drawn its plots, its table and the viewer on a deep-linked episode, the load event, and
# the time ↓ takes to open the next episode.
# Needs a build (build/fetchscope), Debian's chromium and web/node_modules (tools/install-deps.sh).
#   tools/bench-viewer.sh [BUILD_DIR] [EPISODES (1000)] [RUNS (5)]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build}/fetchscope"
episodes="${2:-1000}"
runs="${3:-5}"
seed_episodes=10
chromium="${FETCHSCOPE_CHROMIUM:-/usr/bin/chromium}"
work=$(mktemp -d)
# BENCH_VIEWER_KEEP=1 keeps the runs (their folder is printed)
if [[ -n "${BENCH_VIEWER_KEEP:-}" ]]; then echo "bench-viewer: runs in $work"; else trap 'rm -rf "$work"' EXIT; fi
"$bin" record --env-id FetchPush-v4 --policy scripted --episodes "$seed_episodes" --steps 50 \
  --width 64 --height 64 --quiet --no-report --out "$work/seed"
python3 - "$work/seed" "$work/run" "$episodes" <<'PY'
import json, os, sys
seed, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
os.makedirs(out)
m = json.load(open(os.path.join(seed, "manifest.json")))
source = m["episodes"]
entries = []
for k in range(n):
    text = json.dumps(source[k % len(source)])
    old = "episode_%03d" % source[k % len(source)]["index"]
    new = "episode_%03d" % k
    for name in sorted(os.listdir(seed)):  # the copy's files, hard-linked
        if name.startswith(old + "_") or name.startswith(old + "."):
            os.link(os.path.join(seed, name), os.path.join(out, new + name[len(old):]))
    entry = json.loads(text.replace(old, new))
    entry["index"] = k
    entries.append(entry)
m["episodes"] = entries
m["episodes_requested"] = n
json.dump(m, open(os.path.join(out, "manifest.json"), "w"))
PY
start=$(date +%s.%N)
"$bin" report -q "$work/run"
end=$(date +%s.%N)
last=$((episodes - 1))
node web/test/measure_open.mjs --page "$work/run/index.html" --runs "$runs" \
  --link "episode=$last&t=25" --chromium "$chromium" >"$work/open.json"
python3 - "$work/open.json" "$start" "$end" "$episodes" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
m = r["median"]
print("bench-viewer: %s episodes, index.html %.1f MB, written by report in %.2f s" %
      (sys.argv[4], r["bytes"] / 1e6, float(sys.argv[3]) - float(sys.argv[2])))
print("bench-viewer: opens in %.0f ms (first frame drawn with the plots, table and the viewer on the linked "
      "episode; built by %.0f ms), load event %.0f ms, next episode %.0f ms (medians of %d)" %
      (m["painted_ms"], m["ready_ms"], m["load_ms"], m["next_episode_ms"], len(r["runs"])))
print("bench-viewer: runs %s" % json.dumps(r["runs"]))
if r["errors"]:
    print("bench-viewer: page errors %s" % r["errors"])
    sys.exit(1)
PY
