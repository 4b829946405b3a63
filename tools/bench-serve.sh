#!/usr/bin/env bash
# serve in a browser (BENCHMARKS.md, "serve: live frames"): records a real run of EPISODES
# scripted FetchPush-v4 episodes (50 steps, 64x64 videos; kept in RUN_DIR for later runs), serves
# it with a live env at 640x480, opens the page in headless Chromium RUNS times
# (web/test/measure_serve.mjs: time to the first frame, frames on screen while dragging at 60 Hz,
# a seek, live key steps) and reports serve's peak resident memory. The server side alone is
# `fetchscope bench --what serve`.
# Needs a build (build/fetchscope), Debian's chromium and web/node_modules (tools/install-deps.sh).
#   tools/bench-serve.sh [BUILD_DIR] [EPISODES (1000)] [RUNS (3)] [RUN_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="$(realpath "${1:-build}")/fetchscope"
episodes="${2:-1000}"
runs="${3:-3}"
run="${4:-/tmp/fetchscope-bench-serve-$episodes}"
chromium="${FETCHSCOPE_CHROMIUM:-/usr/bin/chromium}"
if [[ ! -f "$run/manifest.json" ]]; then
  echo "bench-serve: recording $episodes episodes into $run" >&2
  "$bin" record --env-id FetchPush-v4 --policy scripted --episodes "$episodes" --steps 50 \
    --width 64 --height 64 --no-report --quiet --jobs "$(nproc)" --out "$run"
fi
work=$(mktemp -d)
trap 'kill -INT $pid 2>/dev/null; rm -rf "$work"' EXIT
"$bin" serve "$run" --env-id FetchPush-v4 --width 640 --height 480 --port 0 \
  --token-file "$work/token" --save-dir "$work/saved" >"$work/serve.log" 2>&1 &
pid=$!
for _ in $(seq 300); do grep -q 'Ctrl-C stops it' "$work/serve.log" && break; sleep 0.1; done
url=$(sed -n 's/^serve: open //p' "$work/serve.log")
echo "bench-serve: $(grep 'serve: GL' "$work/serve.log")" >&2
for i in $(seq "$runs"); do
  node web/test/measure_serve.mjs --url "$url" --chromium "$chromium" --live-source 1
done
echo "{\"serve_peak_rss_mib\": $(awk '/VmHWM/ {printf "%.1f", $2 / 1024}' /proc/$pid/status), \"episodes\": $episodes}"
