#!/usr/bin/env bash
# The README's first command: install, build, record a demo episode into out/demo.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
tools/configure.sh
cmake --build build -j"$(nproc)" --target fetchscope
build/fetchscope record --env-id FetchPickAndPlace-v4 --policy scripted --seed 0 --episodes 1 \
  --out out/demo --overwrite  # a second run replaces the first
echo "demo written to out/demo: episode_000.mp4, episode_000_sheet.png, episode_000.json, manifest.json, index.html (the run report: open it in a browser)"
