# tools/charts/accuracy.sh — the speed-against-accuracy sweep; sourced by tools/charts.sh
# (uses its ZEPHYR, OUT, WORK, GP, FRAC, REF_COUNT, ACC_SAMPLE, scene, has_method, has_command,
# say, skip).
#
# For each fraction width in FRAC: the SIMD primary pass at --frac-bits N (cycles per primary
# pass, .simd.cycles.totalCycles, and the render's host time, .phases.render, from the render
# report) and its accuracy from `zephyr accuracy --json` against the exact 128-bit reference:
# % of pixels with a wrong first object (firstObjectDiffersPercent), max and mean error in t
# (tMaxError, tMeanError) over a random sample of ACC_SAMPLE pixels, and the PSNR of the final
# image against the sequential method in double over every pixel (psnrDb; "inf" = identical).
# Both run with --uncertain keep: the array's own answer, before the host repairs the pixels it
# flagged (with the default, auto — refine, then recompute —, every pixel is exact by construction, docs/simd.md).
# The planner's own choice (no --frac-bits) is one more row, marked planned=1. The sequential
# tracer in float32 and float64 adds two points (host time of the render): `zephyr accuracy
# --method seq --precision float|double` compares their primary hits with the same exact
# reference over the same sampled pixels, and their image with seq float64 (inf for float64
# itself, and for float32 when its 8-bit image is identical).

ACC=$OUT/accuracy.csv
echo "kind,frac_bits,cycles,host_s,pct_wrong,t_err_max,t_err_mean,psnr,planned" >"$ACC"
# Uncertain pixels the SIMD pass flags (.simd.uncertain of the render report), by width.
UNC=$OUT/uncertain_pixels.csv
echo "fraction bits,overflow,grazing,near tie" >"$UNC"
JQ_UNC='.simd.uncertain // {} | [.overflow, .grazing, .nearTie]
  | map(if . == null then "NaN" else tostring end) | join(",")'
JQ_ACC='[.firstObjectDiffersPercent, .tMaxError, .tMeanError,
         (.psnrDb | if . == "inf" then "Inf" else . end)]
  | map(if . == null then "NaN" else tostring end) | join(",")'

acc_scene=$(scene "$REF_COUNT")
# accuracy_row KIND FRAC PLANNED [flags...] — one render (+ one accuracy run), one row.
accuracy_row() {
  local kind=$1 bits=$2 planned=$3; shift 3
  local rj=$WORK/acc-render-$kind-$bits.json aj=$WORK/acc-$kind-$bits.json
  local method=simd; [ "$kind" = fixed ] || method=seq
  local extra=(); [ $method = simd ] && extra=(--uncertain keep)
  if ! "$ZEPHYR" render --method $method --scene "$acc_scene" --report "$rj" --no-progress \
       "${extra[@]}" "$@" >"$WORK/last.log" 2>&1; then
    say "failed: render --method $method $*"; tail -n 5 "$WORK/last.log" >&2; return 0
  fi
  local cycles host acc="NaN,NaN,NaN,NaN"
  cycles=$(jq -r '.simd.cycles.totalCycles // "NaN"' "$rj")
  host=$(jq -r '.phases.render' "$rj")
  local accFlags=(--uncertain keep "$@")  # the same flags as the render
  [ $method = seq ] && accFlags=(--method seq "$@")
  if has_command accuracy && "$ZEPHYR" accuracy "$acc_scene" --json --sample "$ACC_SAMPLE" \
       "${accFlags[@]}" >"$aj" 2>"$WORK/last.log"; then
    acc=$(jq -r "$JQ_ACC" "$aj")
  else
    say "no accuracy figures for $kind $bits"; tail -n 5 "$WORK/last.log" >&2
  fi
  echo "$kind,$bits,$cycles,$host,$acc,$planned" >>"$ACC"
  if [ "$kind" = fixed ]; then
    local label=$bits; [ "$planned" = 1 ] && label=$(jq -r '.simd.plan.fracBits' "$rj")
    [ "$planned" = 0 ] && echo "$bits,$(jq -r "$JQ_UNC" "$rj")" >>"$UNC"
    [ "$planned" = 1 ] && sed -i "s/^fixed,planned,/fixed,$label,/" "$ACC"
  fi
  return 0
}

ACC_NOTE="$REF_COUNT random spheres, ${SIZE}x${SIZE}, seed $SEED; labels = fraction bits; --uncertain keep (the array answer, unrepaired); $CPU, $(date +%Y-%m-%d)"
ACC_NOTE2="first object, t: $ACC_SAMPLE sampled pixels vs the exact 128-bit reference (zephyr accuracy --sample)"
ACC_NOTE3="seq float32/float64 too (zephyr accuracy --method seq). PSNR: every pixel vs seq float64 (identical = inf, not drawn; float64 is that reference)"
if has_method simd && has_command accuracy; then
  for bits in $FRAC; do accuracy_row fixed "$bits" 0 --frac-bits "$bits"; done
  accuracy_row fixed planned 1
else
  skip "speed vs accuracy sweep (needs render --method simd and zephyr accuracy)"
  ACC_NOTE="SIMD method or zephyr accuracy not available (skipped). $ACC_NOTE"
fi
if has_method seq; then
  accuracy_row float32 NaN 0 --precision float
  accuracy_row float64 NaN 0 --precision double
fi

for spec in "5:pct_wrong:% of pixels with a wrong first object:0" \
            "6:t_error:max error in t (scene units):1" \
            "8:psnr:PSNR of the image against seq float64 (dB):0"; do
  IFS=: read -r xcol tag xl logx <<<"$spec"
  acc_empty=1  # no measured point on this accuracy axis (a log axis needs one above 0)
  awk -F, -v c="$xcol" -v lg="$logx" 'NR > 1 && $c != "NaN" && (!lg || $c > 0) { f = 1 } END { exit !f }' "$ACC" \
    && acc_empty=0
  gnuplot -e "in='$ACC'; out='$OUT/speed_vs_accuracy_$tag.png'; xcol=$xcol; logx=$logx; \
ttl='Speed against accuracy: $xl'; xl='$xl'; note='$ACC_NOTE'; note2='$ACC_NOTE2'; note3='$ACC_NOTE3'; empty=$acc_empty" "$GP/accuracy.gp" \
    2> >(grep -v "Skipping data file with no valid points" >&2)
  say "wrote $OUT/speed_vs_accuracy_$tag.png"
done
chart uncertain_pixels "Uncertain pixels the SIMD pass detects, by fraction width" \
  "fraction bits (--frac-bits)" "pixels" 0 0 "$(note_for simd)" \
  "overflow / grazing (discriminant within the error bound of 0) / near tie (two t within the bound)"
