#!/usr/bin/env bash
# Remakes README's pictures with the tool itself: docs/pick_and_place.png and
# docs/push_three_views.png (render), docs/viewer.png: the report's episode viewer opened by the
# deep link index.html#episode=2&t=16 on a scripted FetchPickAndPlace-v4 run (5 episodes of 30
# steps at 240x240; web/test/check_viewer.mjs photographs the viewer element),
# docs/report.png and docs/compare.png: two record runs of
# FetchPush-v4, 5 episodes of 20 steps each (the scripted policy reaches the goal in time in
# some episodes and not in others, so the report shows successes and failures; the zero policy
# never moves), the scripted run's report and the comparison of the two. Headless Chromium
# (through playwright-core, as in the browser tests: web/test/check_page.mjs) photographs each
# whole page once its videos are loaded and shown at 70 % of their length.
# docs/contacts.png and docs/contacts_plot.png: a scripted FetchPickAndPlace grasp at step 16 with
# --overlay default,contacts, and the viewer's finger-force plot of that episode.
# docs/golden_review.png: golden check's review page after the block's red went 0.2 -> 0.25 (the
# bundled models copied with that one change; a same-backend check fails it), photographed by
# web/test/check_golden_review.mjs.
# docs/randomized_looks.png: one step under 16 randomized looks, tiled 4x4
# (tools/randomized-looks-sheet.sh).
# Needs a build (build/fetchscope), Debian's chromium and web/node_modules (tools/install-deps.sh).
# `tools/docs-screenshots.sh BUILD OUT golden` makes only the golden review page's picture,
# `tools/docs-screenshots.sh BUILD OUT looks` only the randomized looks' sheet.
#   tools/docs-screenshots.sh [BUILD_DIR] [OUT_DIR (default docs)]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build}/fetchscope"
out="${2:-docs}"
chromium="${FETCHSCOPE_CHROMIUM:-/usr/bin/chromium}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
golden_review() {  # the block's red 0.2 -> 0.25 in a copy of the goldens' assets, checked
  cp -r golden "$work/golden"
  mkdir -p "$work/golden/redder/fetch"
  cp models/*.xml "$work/golden/redder/fetch/"
  sed -i 's|name="block_mat" rgba="0.2 0.2 0.2 1"|name="block_mat" rgba="0.25 0.2 0.2 1"|' \
    "$work/golden/redder/fetch/fetch_shared.xml"
  python3 -c 'import json, sys
m = json.load(open(sys.argv[1]))
for s in m["scenes"]:
    if s["name"] == "push_reset_external": s["assets"] = "redder"
json.dump(m, open(sys.argv[1], "w"), indent=1)' "$work/golden/manifest.json"
  FETCHSCOPE_SHARED_DIR="$work/none" "$bin" golden check --backend osmesa --golden-dir "$work/golden" \
    --only push_reset_external,reach_reset,slide_reset --out "$work/golden-out" >/dev/null || [[ $? -eq 1 ]]
  node web/test/check_golden_review.mjs --page "$work/golden-out/index.html" \
    --screenshot "$out/golden_review.png" --chromium "$chromium" >"$work/golden.json"
  grep -q '"console_errors":\[\],"page_errors":\[\]' "$work/golden.json" ||
    { cat "$work/golden.json" >&2; echo "docs-screenshots: the golden review page has errors" >&2; exit 1; }
}
if [[ "${3:-}" == looks ]]; then
  tools/randomized-looks-sheet.sh "${1:-build}" "$out/randomized_looks.png"
  exit 0
fi
golden_review
if [[ "${3:-}" == golden ]]; then echo "docs-screenshots: $out/golden_review.png"; exit 0; fi
common=(--env-id FetchPush-v4 --episodes 5 --steps 20 --width 240 --height 240 --quiet)
"$bin" record "${common[@]}" --policy scripted --out "$work/scripted"
"$bin" record "${common[@]}" --policy zero --out "$work/zero"
"$bin" compare -q "$work/scripted" "$work/zero" --out "$work/compare" || [[ $? -eq 1 ]]
shoot() {  # PAGE PNG: the whole page; a failed check (console error, no page) fails the script
  node web/test/check_page.mjs --page "$1" --screenshot "$2" --seek 0.7 --chromium "$chromium" \
    >"$work/check.json" || { cat "$work/check.json" >&2; exit 1; }
  if ! grep -q '"console_errors":\[\],"page_errors":\[\]' "$work/check.json"; then
    cat "$work/check.json" >&2
    echo "docs-screenshots: $1 has errors" >&2
    exit 1
  fi
}
shoot "$work/scripted/index.html" "$out/report.png"
shoot "$work/compare/index.html" "$out/compare.png"
# the episode viewer at a deep-linked step: the gripper closing on the block
"$bin" record --env-id FetchPickAndPlace-v4 --policy scripted --episodes 5 --steps 30 \
  --width 240 --height 240 --quiet --out "$work/pick"
mkdir -p "$work/grabs"
node web/test/check_viewer.mjs --page "$work/pick/index.html" --links 2:16 --grab-dir "$work/grabs" \
  --screenshot "$out/viewer.png" --chromium "$chromium" >"$work/viewer.json" ||
  { cat "$work/viewer.json" >&2; exit 1; }
if ! grep -q '"console_errors":\[\],"page_errors":\[\]' "$work/viewer.json"; then
  cat "$work/viewer.json" >&2
  echo "docs-screenshots: the viewer page has errors" >&2
  exit 1
fi
# the README's first two pictures: frames as `render` draws them
"$bin" render --env-id FetchPickAndPlace-v4 --policy scripted --seed 0 --steps 30 \
  --overlay goal,achieved,hud,action,trail --width 480 --height 480 -o "$out/pick_and_place.png" >/dev/null
"$bin" render --env-id FetchPush-v4 --policy scripted --seed 0 --steps 8 \
  --camera default,external_camera_0,track --width 320 --height 320 -o "$out/push_three_views.png" >/dev/null
# contacts: a scripted grasp with --overlay contacts, and the viewer's finger-force plot
camera="track:body=object0,distance=0.6,azimuth=150,elevation=-20"
"$bin" render --env-id FetchPickAndPlace-v4 --policy scripted --seed 0 --steps 16 \
  --overlay default,contacts --camera "$camera" --width 480 --height 360 -o "$out/contacts.png" >/dev/null
"$bin" record --env-id FetchPickAndPlace-v4 --policy scripted --episodes 1 --steps 30 \
  --width 240 --height 240 --signals contacts --overlay default,contacts --camera "$camera" \
  --quiet --out "$work/contacts"
node web/test/shoot_element.mjs --page "$work/contacts/index.html#episode=0&t=16" \
  --selector "#vplot-contacts" --out "$out/contacts_plot.png" --chromium "$chromium" >"$work/plot.json"
grep -q '"console_errors":\[\],"page_errors":\[\]' "$work/plot.json" ||
  { cat "$work/plot.json" >&2; echo "docs-screenshots: the contacts plot has errors" >&2; exit 1; }
# serve's step inspector: a scripted PickAndPlace recording at step 17 (web/test/check_serve_debug.mjs
# photographs the side column: the episode list, the inspector and obs[5]'s plot)
"$bin" record --env-id FetchPickAndPlace-v4 --policy scripted --seed 2 --episodes 1 --steps 50 \
  --signals contacts --width 64 --height 64 --no-sheets --quiet --out "$work/served"
"$bin" serve "$work/served" --env-id FetchPickAndPlace-v4 --seed 5 --policy scripted --port 0 \
  --width 480 --height 360 --token-file "$work/token" --save-dir "$work/saved" >"$work/serve.log" 2>&1 &
serve_pid=$!
for _ in $(seq 150); do grep -q 'Ctrl-C stops it' "$work/serve.log" && break; sleep 0.2; done
url=$(sed -n 's|^serve: open \(http://.*\)$|\1|p' "$work/serve.log")
node web/test/check_serve_debug.mjs --url "$url" --out "$work" --steps 17 --chromium "$chromium" \
  >"$work/debug.json" || true
kill -INT "$serve_pid"; wait "$serve_pid" || true
grep -q '"console_errors":\[\],"page_errors":\[\]' "$work/debug.json" && [[ -f "$work/inspector.png" ]] ||
  { cat "$work/debug.json" >&2; echo "docs-screenshots: the serve page has errors" >&2; exit 1; }
cp "$work/inspector.png" "$out/serve_inspector.png"
tools/randomized-looks-sheet.sh "${1:-build}" "$out/randomized_looks.png" >/dev/null
echo "docs-screenshots: $out/report.png $out/compare.png $out/viewer.png $out/pick_and_place.png $out/push_three_views.png $out/contacts.png $out/contacts_plot.png $out/serve_inspector.png $out/golden_review.png $out/randomized_looks.png"
