#!/usr/bin/env bash
# What BENCHMARKS.md's GPU-node figures come from: one short script run on a GPU node with the
# bundle (tools/bundle.sh) unpacked, printing every figure and writing the JSON beside it.
#   tools/measure-gpu-node.sh FETCHSCOPE OUT_DIR [GENUINE_ASSETS]
# FETCHSCOPE: the bundle's launcher (or a build's binary); run from the repository root (the
# goldens are read from golden/). About 5 minutes on 16 cores. Parts:
#   node     `bench --what node --backends egl`: render and record throughput, the recommendation
#   golden   `golden check --backend egl` (genuine-asset scenes only when GENUINE_ASSETS is given)
#   jobs     the same 4 episodes with --jobs 1 and --jobs 4 on the GPU: identical bytes?
#   webm     16 FetchPush episodes at 480x480, --jobs 8, mp4 against webm, alternating, twice
#   minari   10,000 scripted FetchPush episodes with `rollout --jobs 16`, trajectory JSON against
#            a Minari dataset, alternating, twice
#   record16 `record --jobs 16`, 64 FetchPush episodes at 480x480 (libx264), this binary against
#            $OLD_FETCHSCOPE (another build's launcher, e.g. the binary before a change),
#            alternating, twice; then this binary with --overlay default,contacts and
#            --signals contacts once
#   serve    `bench --what serve --backends egl` at 640x480 and 1280x720: serve's frame budget
# PARTS="golden minari" runs only those parts (default: node golden jobs webm minari).
set -uo pipefail
fs=$1
out=$2
genuine=${3:-}
mkdir -p "$out"
work=$(mktemp -d)
log() { echo "== $* ($(date -u +%H:%M:%S))"; }
TIMEFORMAT='%R s wall, %U s user, %S s sys'
parts=" ${PARTS:-node golden jobs webm minari} "
want() { [[ $parts == *" $1 "* ]]; }

log "machine"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 | head -2
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo)"
"$fs" --version 2>&1 | head -3

if want node; then
log "node"
"$fs" bench --what node --backends egl --json-out "$out/node.json" 2>&1 | tail -40
fi

if want golden; then
log "golden"
golden_args=(--backend egl --out "$work/golden")
[[ -n $genuine ]] && golden_args+=(--genuine-assets "$genuine")
"$fs" golden check "${golden_args[@]}" 2>&1 | tail -20
fi

if want jobs; then
log "jobs"
for j in 1 4; do
  "$fs" record --env-id FetchPush-v4 --episodes 4 --jobs "$j" --format mp4,webm --quiet \
    --out "$work/jobs$j" >/dev/null 2>&1 || echo "record --jobs $j failed"
done
(cd "$work/jobs1" && sha256sum episode_*.mp4 episode_*.webm episode_*.json) >"$work/j1.sum"
(cd "$work/jobs4" && sha256sum episode_*.mp4 episode_*.webm episode_*.json) >"$work/j4.sum"
if cmp -s "$work/j1.sum" "$work/j4.sum"; then
  echo "jobs: --jobs 1 and --jobs 4 wrote identical bytes ($(wc -l <"$work/j1.sum") files)"
else
  echo "jobs: DIFFERENT bytes"; diff "$work/j1.sum" "$work/j4.sum" | head
fi
fi

if want webm; then
log "webm"
for round in 1 2; do
  for f in mp4 webm; do
    echo -n "round $round $f: "
    { time "$fs" record --env-id FetchPush-v4 --episodes 16 --jobs 8 --width 480 --height 480 \
        --format "$f" --quiet --overwrite --out "$work/fmt_$f" >/dev/null; } 2>&1
  done
done
du -sb "$work"/fmt_mp4/episode_*.mp4 | awk '{s+=$1} END {print "mp4 bytes", s}'
du -sb "$work"/fmt_webm/episode_*.webm | awk '{s+=$1} END {print "webm bytes", s}'
fi

if want minari; then
log "minari"
export MINARI_DATASETS_PATH=$work/minari
for round in 1 2; do
  echo -n "round $round json: "
  { time "$fs" rollout --env-id FetchPush-v4 --policy scripted --episodes 10000 --jobs 16 \
      --json-out "$work/push10k.json" >/dev/null; } 2>&1
  echo -n "round $round minari: "
  { time "$fs" rollout --env-id FetchPush-v4 --policy scripted --episodes 10000 --jobs 16 \
      --minari fetchscope/FetchPush/scripted-v0 --overwrite >/dev/null; } 2>&1
done
ls -l "$work/push10k.json" "$MINARI_DATASETS_PATH/fetchscope/FetchPush/scripted-v0/data/"
fi
if want record16; then
log "record16"
old=${OLD_FETCHSCOPE:-}
for round in 1 2; do
  for which in new old; do
    bin=$fs
    if [[ $which == old ]]; then [[ -n $old ]] || continue; bin=$old; fi
    echo -n "round $round $which: "
    { time "$bin" record --env-id FetchPush-v4 --episodes 64 --jobs 16 --codec libx264 \
        --width 480 --height 480 --quiet --no-report --out "$work/r16_${which}_$round" \
        >/dev/null; } 2>&1
  done
done
echo -n "contacts (overlay and signals): "
{ time "$fs" record --env-id FetchPush-v4 --episodes 64 --jobs 16 --codec libx264 --width 480 \
    --height 480 --overlay default,contacts --signals contacts --quiet --no-report \
    --out "$work/r16_contacts" >/dev/null; } 2>&1
if [[ -n $old ]]; then
  (cd "$work/r16_new_1" && sha256sum episode_*) >"$work/new.sum"
  (cd "$work/r16_old_1" && sha256sum episode_*) >"$work/old.sum"
  cmp -s "$work/new.sum" "$work/old.sum" && echo "record16: old and new wrote identical bytes" ||
    echo "record16: old and new bytes DIFFER"
fi
fi

if want serve; then
log "serve"
"$fs" bench --what serve --backends egl --seconds 9 --json-out "$out/serve.json" 2>&1 | grep serve
"$fs" bench --what serve --backends egl --seconds 6 --serve-width 1280 --serve-height 720 \
  --json-out "$out/serve720.json" 2>&1 | grep serve
fi
log "done"
rm -rf "$work"
