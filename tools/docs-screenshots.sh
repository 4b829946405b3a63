#!/usr/bin/env bash
# Remakes README's docs/report.png and docs/compare.png with the tool itself: two record runs of
# FetchPush-v4 (scripted and zero policy, 30 steps: some scripted episodes are not done yet), their report and their comparison, photographed by
# headless Chromium. Needs a build (build/fetchscope) and Debian's chromium.
#   tools/docs-screenshots.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build}/fetchscope"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
common=(--env-id FetchPush-v4 --episodes 10 --steps 30 --width 240 --height 240 --quiet)
"$bin" record "${common[@]}" --policy scripted --out "$work/scripted"
"$bin" record "${common[@]}" --policy zero --out "$work/zero"
"$bin" compare -q "$work/scripted" "$work/zero" --out "$work/compare" || [[ $? -eq 1 ]]
shoot() {  # PAGE PNG HEIGHT
  chromium --headless --no-sandbox --disable-gpu --disable-background-networking \
    --disable-component-update --no-first-run --user-data-dir="$work/profile" --hide-scrollbars \
    --window-size=1280,"$3" --virtual-time-budget=10000 --screenshot="$2" "file://$1" 2>/dev/null
}
shoot "$work/scripted/index.html" docs/report.png 2000
shoot "$work/compare/index.html" docs/compare.png 1900
echo "docs-screenshots: docs/report.png docs/compare.png"
