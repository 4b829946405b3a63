#!/usr/bin/env bash
# Writes the JSON outputs of a fixed set of commands into OUT_DIR, with the fields that are
# allowed to differ between two builds (timings, versions, paths, dates) removed, so that two
# builds can be compared number for number:
#   tools/snapshot-outputs.sh OLD_BINARY /tmp/before
#   tools/snapshot-outputs.sh build/fetchscope /tmp/after
#   tools/snapshot-outputs.sh --compare /tmp/before /tmp/after
# --compare checks that every key and value of the first snapshot is in the second (new keys may
# be added, none removed, no value changed) and exits 1 naming the first difference otherwise.
set -euo pipefail
if [[ "${1:-}" == "--compare" ]]; then
  exec python3 - "$2" "$3" <<'PY'
import json, os, sys
before, after = sys.argv[1], sys.argv[2]
def walk(a, b, path):
    if isinstance(a, dict):
        if not isinstance(b, dict):
            return f"{path}: was an object"
        for k, v in a.items():
            if k not in b:
                return f"{path}/{k}: key removed"
            d = walk(v, b[k], f"{path}/{k}")
            if d:
                return d
        return None
    if isinstance(a, list):
        if not isinstance(b, list) or len(a) != len(b):
            return f"{path}: list length {len(a)} -> {len(b) if isinstance(b, list) else 'not a list'}"
        for i, (x, y) in enumerate(zip(a, b)):
            d = walk(x, y, f"{path}[{i}]")
            if d:
                return d
        return None
    if type(a) != type(b) or repr(a) != repr(b):
        return f"{path}: {a!r} -> {b!r}"
    return None
bad = 0
names = sorted(os.listdir(before))
for name in names:
    other = os.path.join(after, name)
    if not os.path.exists(other):
        print(f"{name}: missing in {after}"); bad += 1; continue
    if name.endswith(".json"):
        d = walk(json.load(open(os.path.join(before, name))), json.load(open(other)), name)
    else:
        d = None if open(os.path.join(before, name), "rb").read() == open(other, "rb").read() else f"{name}: bytes differ"
    if d:
        print(d); bad += 1
print(f"snapshot compare: {len(names)} files, {bad} differing")
sys.exit(1 if bad else 0)
PY
fi
bin=$(realpath "$1")
out=$(realpath -m "$2")
rm -rf "$out"
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
run() {  # run NAME ARGS...: stdout into NAME (exit status kept in NAME.status)
  local name=$1
  shift
  set +e
  "$bin" "$@" >"$out/$name" 2>/dev/null
  echo $? >"$out/$name.status"
  set -e
}
"$bin" list-envs --json >"$out/list_envs.json"
for id in FetchReach-v4 FetchReachDense-v4 FetchPush-v4 FetchPushDense-v4 FetchPickAndPlace-v4 \
  FetchPickAndPlaceDense-v4 FetchSlide-v4 FetchSlideDense-v4; do
  run "describe_$id.json" describe --env-id "$id"
  run "rollout_scripted_$id.json" rollout --env-id "$id" --policy scripted --episodes 2 --seed 5
  run "random_$id.json" random-episodes --env-id "$id" --n-episodes 3 --seed 7
  "$bin" reward-check --env-id "$id" --n-steps 120 --seed 2 --json-out "$work/rc_$id.json" >/dev/null
  cp "$work/rc_$id.json" "$out/reward_check_$id.json"
done
run rollout_random_push.json rollout --env-id FetchPush-v4 --policy random --episodes 3 --seed 11
run rollout_zero_slide.json rollout --env-id FetchSlide-v4 --policy zero --episodes 1 --seed 4
run rollout_jobs2.json rollout --env-id FetchPickAndPlace-v4 --policy random --episodes 4 --seed 3 --jobs 2
"$bin" probe-actions --env-id FetchPickAndPlace-v4 --steps 6 --out "$work/probe" >/dev/null 2>&1
for f in "$work"/probe/*.json; do cp "$f" "$out/probe_$(basename "$f")"; done
"$bin" anatomy --env-id FetchPush-v4 --out "$work/anatomy" >/dev/null 2>&1
for f in "$work"/anatomy/*.json; do cp "$f" "$out/anatomy_$(basename "$f")"; done
"$bin" record --env-id FetchPush-v4 --policy scripted --episodes 2 --seed 1 --width 96 --height 72 \
  --out "$work/run" --quiet >/dev/null 2>&1
for f in "$work"/run/episode_*.json; do cp "$f" "$out/record_$(basename "$f")"; done
"$bin" render --env-id FetchPickAndPlace-v4 --policy scripted --steps 7 --width 64 --height 48 \
  --layers rgb,depth,segmentation -o "$work/frame.png" >/dev/null 2>&1
for f in "$work"/frame*.json; do [[ -f "$f" ]] && cp "$f" "$out/render_$(basename "$f")"; done
# manifest: only the fields that describe the run, not the machine or the clock
python3 - "$work/run/manifest.json" "$out/record_manifest.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
for k in ("timings", "timings_s", "versions", "created", "command_line", "gl", "hostname", "out", "wall_s",
          "encoder", "encoder_reason", "started", "finished", "duration_s", "machine"):
    m.pop(k, None)
json.dump(m, open(sys.argv[2], "w"), indent=1, sort_keys=True)
PY
# drop machine-dependent fields from every snapshot (assets paths are this checkout's)
python3 - "$out" <<'PY'
import json, os, sys
def strip(x):
    if isinstance(x, dict):
        return {k: (os.path.basename(v) if k == "model_file" else strip(v)) for k, v in x.items()
                if k not in ("path", "pid", "versions", "timings", "fetchscope_version", "mujoco_version")}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x
for name in os.listdir(sys.argv[1]):
    p = os.path.join(sys.argv[1], name)
    if name.endswith(".json") and os.path.getsize(p):
        try:
            j = json.load(open(p))
        except ValueError:
            continue
        json.dump(strip(j), open(p, "w"), indent=1, sort_keys=True)
PY
echo "snapshot: $(ls "$out" | wc -l) files in $out"
