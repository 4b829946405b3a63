#!/usr/bin/env bash
# docs/randomized_looks.png (docs/guide/recording.md, "Randomized looks"): one step of one task
# under 16 randomized looks, tiled 4x4. Each tile is `fetchscope render --randomize
# colors,textures,lighting,camera` of FetchPickAndPlace-v4, scripted policy, step 10 (the
# fingers round the block), a camera following the block (track:body=object0, so it is in the
# middle of every tile), 240x240, overlays off, --seed 0 and --look-seed 0..15: the same state
# in every tile (the seed places the block and the goal), each under the look LookSeed(N, 0).
# Tiled, each tile labelled with its look seed,
# by Debian's python3-pil. Called by tools/docs-screenshots.sh; on its own:
#   tools/randomized-looks-sheet.sh [BUILD_DIR (default build)] [OUT_PNG (default docs/randomized_looks.png)]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build}/fetchscope"
out="${2:-docs/randomized_looks.png}"
python="${FETCHSCOPE_PIL_PYTHON:-/usr/bin/python3}"  # Debian's, where python3-pil is
camera="track:body=object0,distance=0.7,azimuth=150,elevation=-25"  # the block in the middle
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for seed in $(seq 0 15); do
  "$bin" render --env-id FetchPickAndPlace-v4 --policy scripted --seed 0 --look-seed "$seed" --steps 10 \
    --camera "$camera" --overlay none --width 240 --height 240 \
    --randomize colors,textures,lighting,camera -o "$work/look_$seed.png" >/dev/null
done
"$python" - "$work" "$out" <<'PY'
import sys
from PIL import Image, ImageDraw
work, out = sys.argv[1], sys.argv[2]
tile, gap, cols = 240, 4, 4
sheet = Image.new("RGB", (cols * tile + (cols - 1) * gap, cols * tile + (cols - 1) * gap), "white")
for seed in range(16):
    image = Image.open(f"{work}/look_{seed}.png").convert("RGB")
    draw = ImageDraw.Draw(image)
    draw.rectangle([0, 0, 92, 14], fill="black")
    draw.text((3, 2), f"--look-seed {seed}", fill="white")
    sheet.paste(image, ((seed % cols) * (tile + gap), (seed // cols) * (tile + gap)))
sheet.save(out, optimize=True)
PY
echo "randomized-looks-sheet: $out"
