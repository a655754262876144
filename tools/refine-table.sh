#!/usr/bin/env bash
# The refine-pass table of docs/simd.md: per scene, the SIMD pass's uncertain pixels, what
# the refine pass (--uncertain refine) leaves to the host, and the cycles of each pass.
#
#   [SCENES=DIR] tools/refine-table.sh ZEPHYR [SIZE] [WORKDIR]   SIZE e.g. 256 (default)
#
# Scenes: the generated ones (spheres, flake, showcase) and every NFF scene in SCENES (e.g. a
# folder of Eric Haines' SPD scenes), all rendered at SIZE×SIZE. Prints a Markdown table.
# ACCURACY=1 adds a column from `zephyr accuracy --uncertain refine` over every pixel: the
# pixels whose first object still differs from the exact 128-bit reference after the refine
# pass and the host's repair (the target is 0; slow: minutes per scene at 256×256).
set -euo pipefail
zephyr=${1:?usage: tools/refine-table.sh ZEPHYR [SIZE] [WORKDIR]}
size=${2:-256}
work=${3:-$(mktemp -d)}
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work"
"$zephyr" gen spheres --count 64 --seed 1 --size "${size}x$size" --out "$work/spheres.nff" >/dev/null
"$zephyr" gen flake --depth 3 --size "${size}x$size" --out "$work/flake.nff" >/dev/null
"$zephyr" gen showcase --size "${size}x$size" --out "$work/showcase.nff" >/dev/null
if [ -n "${SCENES:-}" ] && [ -d "$SCENES" ]; then
  for f in "$SCENES"/*.nff; do
    sed "s/^resolution .*/resolution $size $size/" "$f" > "$work/$(basename "$f")"
  done
fi
head="| scene ($size×$size) | pixels | uncertain after the first pass (refined) | still uncertain → host | first-pass cycles | refine cycles | refine / first |"
rule="|---|---|---|---|---|---|---|"
if [ -n "${ACCURACY:-}" ]; then head="$head first object differs after repair |"; rule="$rule---|"; fi
echo "$head"
echo "$rule"
for scene in "$work"/*.nff; do
  name=$(basename "$scene" .nff)
  "$zephyr" render --method simd "$scene" --uncertain refine --out "$work/$name.png" \
    --report "$work/$name.json" --no-progress >/dev/null 2>&1
  jq -r --arg n "$name" --argjson px $((size * size)) '
    .simd as $s | ($s.refine.pixels // 0) as $u
    | ($s.refine.cycles.totalCycles // 0) as $rc
    | "| \($n) | \($px) | \($u) (\(100 * $u / $px * 100 | round / 100) %) | \($s.uncertain.recomputed) (\(100 * $s.uncertain.recomputed / $px * 100 | round / 100) %) | \($s.cycles.totalCycles) | \($rc) | \(100 * $rc / $s.cycles.totalCycles | round) % |"' \
    "$work/$name.json" | tr -d '\n'
  if [ -n "${ACCURACY:-}" ]; then
    "$zephyr" accuracy "$scene" --uncertain refine --json > "$work/$name.accuracy.json" 2>/dev/null
    jq -r '" \(.firstObjectDiffers) |"' "$work/$name.accuracy.json" | tr -d '\n'
  fi
  echo
done
