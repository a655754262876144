#!/usr/bin/env bash
# tools/charts/fixed_vs_float.sh — fixed point against floating point on the emulated array
# (issue 16; docs/results.md, "Fixed against float on the array"): the SIMD primary pass at
# fixed fraction widths (--frac-bits B) and in bit-serial float formats (--number float
# --float-format eXmY), and the sequential host tracers in float32 and float64, each as
# cycles per primary pass (host seconds for the host tracers) against the % of pixels whose
# first object differs from the exact 128-bit reference and the PSNR of the image against
# seq float64. Every point is one `zephyr accuracy --json` run (its cycles, hostSeconds,
# firstObjectDiffersPercent, tMaxError, psnrDb); the array runs with --uncertain keep, the
# array's own answer before the host repairs the pixels it flagged.
#
#   bash tools/charts/fixed_vs_float.sh             # 64 random spheres, 384x384 (the chart)
#   SIZE=128 bash tools/charts/fixed_vs_float.sh    # quicker
# Environment: SIZE, COUNT (64), SEED (1), SAMPLE (pixels the first-object error samples;
# default every pixel), FRAC, FLOATS (the widths and formats), ZEPHYR, OUT (docs/results);
# REDRAW=1 draws the charts from the CSV already in OUT without running anything.
# Writes OUT/fixed_vs_float.csv, OUT/fixed_vs_float_pct_wrong.png, OUT/fixed_vs_float_psnr.png.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
ZEPHYR=${ZEPHYR:-$ROOT/build/bin/zephyr}
OUT=${OUT:-$ROOT/docs/results}
SIZE=${SIZE:-384} COUNT=${COUNT:-64} SEED=${SEED:-1} SAMPLE=${SAMPLE:-0}
FRAC=${FRAC:-"6 8 10 12 16 20"}
FLOATS=${FLOATS:-"e5m7 e5m10 e6m12 e6m16 e8m23"}
for tool in jq gnuplot; do command -v "$tool" >/dev/null || { echo "$tool not found (tools/setup.sh)" >&2; exit 1; }; done
[ -x "$ZEPHYR" ] || { echo "$ZEPHYR not built (make binaries)" >&2; exit 1; }
mkdir -p "$OUT"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/zephyr-fvf.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
scene=$WORK/spheres.nff
"$ZEPHYR" gen spheres --count "$COUNT" --seed "$SEED" --size "${SIZE}x${SIZE}" --out "$scene"

CSV=$OUT/fixed_vs_float.csv
if [ -z "${REDRAW:-}" ]; then
echo "kind,label,cycles,host_s,pct_wrong,t_err_max,psnr,grazing,near_tie" >"$CSV"
JQ='[.cycles // "NaN", .hostSeconds, .firstObjectDiffersPercent, .tMaxError,
     (.psnrDb | if . == "inf" then "Inf" else . end),
     (.uncertain.grazing // "NaN"), (.uncertain.nearTie // "NaN")]
   | map(tostring) | join(",")'
point() {  # point KIND LABEL FLAGS...
  local kind=$1 label=$2; shift 2
  "$ZEPHYR" accuracy "$scene" --json --sample "$SAMPLE" "$@" >"$WORK/p.json"
  echo "$kind,$label,$(jq -r "$JQ" "$WORK/p.json")" | tee -a "$CSV" >&2
}
for b in $FRAC; do point fixed "s.$b" --uncertain keep --frac-bits "$b"; done
for f in $FLOATS; do point float "$f" --uncertain keep --number float --float-format "$f"; done
point float "planned" --uncertain keep --number float
planned=$(jq -r '.floatFormat' "$WORK/p.json"); sed -i "s/^float,planned,/float,$planned (planned),/" "$CSV"
point seq float32 --method seq --precision float
point seq float64 --method seq --precision double
fi

NOTE="$COUNT random spheres (zephyr gen spheres --seed $SEED), ${SIZE}x${SIZE}, --uncertain keep; $(date +%Y-%m-%d)"
for spec in "5:pct_wrong:% of pixels with a wrong first object (vs exact 128-bit; 0 drawn at 1e-4):1" \
            "7:psnr:PSNR of the image against seq float64 (dB; float64 itself is the reference, not drawn):0"; do
  IFS=: read -r xcol tag xl logx <<<"$spec"
  hasseq=$(awk -F, -v c="$xcol" '$1 == "seq" && $c != "NaN" && $c != "Inf" { f = 1 } END { print f + 0 }' "$CSV")
  gnuplot -e "in='$CSV'; out='$OUT/fixed_vs_float_$tag.png'; xcol=$xcol; xl='$xl'; note='$NOTE'; logx=$logx; floor=1e-4; hasseq=$hasseq" \
    "$ROOT/tools/charts/fixed_vs_float.gp" 2> >(grep -v "Skipping data file with no valid points" >&2)
  echo "wrote $OUT/fixed_vs_float_$tag.png" >&2
done
