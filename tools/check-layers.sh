#!/usr/bin/env bash
# The layer order, written once: each folder's code may include its own headers and those of the
# folders on its line, never one above it (docs/architecture.md explains the layers). `fetchscope/`
# is the build's generated header (paths), allowed everywhere. Exits 1 naming every include that
# climbs a layer, 0 when there is none. Run by CI (.ci/run) and by ctest (LayerIncludes).
#   tools/check-layers.sh [REPO_ROOT]
set -euo pipefail
root=${1:-"$(cd "$(dirname "$0")/.." && pwd)"}
declare -A allowed=(
  [base]=""
  [src]="base"
  [render]="base src"
  [encode]="base src render"
  [dataset]="base src"
  [run]="base src render encode dataset"
  [inspect]="base src render encode dataset run"
  [serve]="base src render encode dataset run inspect"
  [bench]="base src render encode dataset run inspect serve"
  [cli]="base src render encode dataset run inspect serve bench"
)
order=(base src render encode dataset run inspect serve bench cli)
bad=0 checked=0
for layer in "${order[@]}"; do
  [[ -d "$root/$layer" ]] || { echo "check-layers: no folder $layer/ in $root" >&2; exit 2; }
  ok=" $layer fetchscope ${allowed[$layer]} "
  while IFS= read -r -d '' file; do
    checked=$((checked + 1))
    while IFS=: read -r line target; do
      top=${target%%/*}
      if [[ "$ok" != *" $top "* ]]; then
        echo "check-layers: ${file#"$root"/}:$line includes \"$target\": $layer/ may include only ${allowed[$layer]:-nothing of ours}"
        bad=$((bad + 1))
      fi
    done < <(grep -no '^#include "[^"]*/[^"]*"' "$file" | sed 's/^\([0-9]*\):#include "\(.*\)"$/\1:\2/')
  done < <(find "$root/$layer" \( -name '*.cc' -o -name '*.h' \) -print0 | sort -z)
done
if [[ $bad -ne 0 ]]; then
  echo "check-layers: $bad include(s) climb a layer (order: ${order[*]})"
  exit 1
fi
echo "check-layers: $checked files, no include climbs a layer (order: ${order[*]})"
