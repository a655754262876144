#!/usr/bin/env bash
# tools/charts/recompute.sh — the host's share of a SIMD render against the fraction width
# (issue 15; docs/results.md, "The recompute share"). For each width B in FRAC, each scene and
# each policy P of --uncertain, one `zephyr render --method simd --frac-bits B --uncertain P`,
# read from its --report JSON. P = auto (the default: refine the flagged pixels in a wider
# array pass when they are more than a share of the image, then recompute what is still
# flagged in double on the host; docs/simd.md) and recompute (every flagged pixel on the host).
#   policy             auto or recompute
#   cycles             .simd.cycles.totalCycles: the first array pass (modelled machine cycles)
#   refine_cycles      .simd.refine.cycles.totalCycles: the refine pass's (0 when none ran)
#   refined            .simd.refine.pixels: pixels the refine pass ran on
#   recomputed         .simd.uncertain.recomputed: pixels the host recomputed in double
#   recomputed_pct     recomputed / (width × height) × 100
#   host_recompute_s   .simd.recomputeSeconds − .simd.refine.hostSeconds: host wall time after
#                      the array pass (decoding the matrix, the double recompute), without the
#                      emulator's time for the refine pass
#   array_host_s       .simd.hostSeconds: the emulator's wall time for the first pass
# Scenes: `zephyr gen spheres --count 64 --seed 1`, `zephyr gen showcase` (transformed
# primitives), and with SCENES=DIR the SPD scene DIR/lattice_s1.nff (cylinders and spheres),
# its resolution set to SIZE.
#
#   bash tools/charts/recompute.sh                                  # 128x128, widths 6..20
#   SCENES=DIR bash tools/charts/recompute.sh    # + the SPD lattice (a folder of SPD .nff scenes)
# Environment: SIZE (128), FRAC ("6 8 10 12 14 16 18 20"), SEED (1), SCENES, ZEPHYR,
# OUT (docs/results). Writes OUT/recompute_share.csv and OUT/recompute_share.png.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
ZEPHYR=${ZEPHYR:-$ROOT/build/bin/zephyr}
OUT=${OUT:-$ROOT/docs/results}
SIZE=${SIZE:-128} SEED=${SEED:-1} FRAC=${FRAC:-"6 8 10 12 14 16 18 20"}
for tool in jq gnuplot; do command -v "$tool" >/dev/null || { echo "$tool not found (tools/setup.sh)" >&2; exit 1; }; done
[ -x "$ZEPHYR" ] || { echo "$ZEPHYR not built (make binaries)" >&2; exit 1; }
mkdir -p "$OUT"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/zephyr-recompute.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

names=(spheres64 showcase)
"$ZEPHYR" gen spheres --count 64 --seed "$SEED" --size "${SIZE}x${SIZE}" --out "$WORK/spheres64.nff"
"$ZEPHYR" gen showcase --size "${SIZE}x${SIZE}" --out "$WORK/showcase.nff"
if [ -n "${SCENES:-}" ]; then
  if [ -f "$SCENES/lattice_s1.nff" ]; then
    sed "s/^resolution .*/resolution $SIZE $SIZE/" "$SCENES/lattice_s1.nff" >"$WORK/lattice.nff"
    names+=(lattice)
  else
    echo "recompute: $SCENES/lattice_s1.nff not found; lattice left out" >&2
  fi
fi

CSV=$OUT/recompute_share.csv
echo "scene,policy,frac_bits,cycles,refine_cycles,refined,recomputed,recomputed_pct,host_recompute_s,array_host_s" >"$CSV"
JQ='.simd as $s | ($s.refine // {}) as $r |
  [$s.cycles.totalCycles, ($r.cycles.totalCycles // 0), ($r.pixels // 0), $s.uncertain.recomputed,
   ($s.uncertain.recomputed * 100 / $px), ($s.recomputeSeconds - ($r.hostSeconds // 0)), $s.hostSeconds]
  | map(tostring) | join(",")'
for name in "${names[@]}"; do
  for policy in auto recompute; do
    for b in $FRAC; do
      if ! "$ZEPHYR" render --method simd --scene "$WORK/$name.nff" --frac-bits "$b" --uncertain "$policy" \
           --no-progress --report "$WORK/r.json" --out "$WORK/r.png" >"$WORK/log" 2>&1; then
        echo "recompute: render failed: $name --frac-bits $b --uncertain $policy" >&2; tail -n 5 "$WORK/log" >&2
        continue
      fi
      echo "$name,$policy,$b,$(jq -r --argjson px $((SIZE * SIZE)) "$JQ" "$WORK/r.json")" | tee -a "$CSV" >&2
    done
  done
done

NOTE="${SIZE}x${SIZE}; spheres64: gen spheres --count 64 --seed $SEED; showcase: gen showcase$([ -f "$WORK/lattice.nff" ] && echo "; lattice: SPD lattice_s1 (cylinders)"); $(date +%Y-%m-%d)"
gnuplot -e "in='$CSV'; out='$OUT/recompute_share.png'; note='$NOTE'; scenes='${names[*]}'" \
  "$ROOT/tools/charts/recompute.gp" 2> >(grep -v "Skipping data file with no valid points" >&2)
echo "recompute: wrote $OUT/recompute_share.png" >&2
