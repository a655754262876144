# tools/charts/accuracy.sh — the speed-against-accuracy sweep; sourced by tools/charts.sh
# (uses its ZEPHYR, OUT, WORK, GP, FRAC, REF_COUNT, scene, has_method, has_command, say, skip).
#
# For each fraction width in FRAC: the SIMD primary pass at --frac-bits N (cycles per
# primary pass and emulator host time from the render report), and its accuracy against
# the exact reference (`zephyr accuracy`, JSON): % of pixels with a wrong first object, max
# and mean error in t, PSNR. The sequential tracer in float32 and float64 adds two points
# (host time; accuracy from `zephyr accuracy --method seq` when it supports that). The
# planner's own choice (no --frac-bits) is one more row, marked planned=1.

ACC=$OUT/accuracy.csv
echo "kind,frac_bits,cycles,host_s,pct_wrong,t_err_max,t_err_mean,psnr,planned" >"$ACC"
# Uncertain pixels the SIMD pass detected (its report's "uncertain" counts), by width.
UNC=$OUT/uncertain_pixels.csv
echo "fraction bits,overflow,grazing,near tie,recomputed on the host" >"$UNC"
JQ_UNC='first(.. | objects | select(has("nearTie"))) // {} |
  [.overflow, .grazing, .nearTie, .recomputed] | map(if . == null then "NaN" else tostring end) | join(",")'

# The accuracy figures, wherever the report puts them: keys that name them.
JQ_ACC='
  def num(re): first(paths(numbers) as $p | select(($p[-1] | tostring) | test(re; "i"))
                     | getpath($p)) // null;
  [ num("^(pct|percent)_?wrong|wrong.*(pct|percent)|first_?object.*(pct|percent)|mismatch.*(pct|percent)"),
    num("t_?err.*max|max.*t_?err"), num("t_?err.*mean|mean.*t_?err"), num("psnr") ]
  | map(if . == null then "NaN" else tostring end) | join(",")'
JQ_CYCLES='first(paths(numbers) as $p | select(($p | map(tostring) | join(".")) | test("cycles.*total|total_?cycles"; "i")) | getpath($p)) // null | tostring'

acc_scene=$(scene "$REF_COUNT")
# accuracy_row KIND FRAC PLANNED [flags...] — one render + one accuracy run, one row.
accuracy_row() {
  local kind=$1 bits=$2 planned=$3; shift 3
  local rj=$WORK/acc-render-$kind-$bits.json aj=$WORK/acc-$kind-$bits.json
  local method=simd; [ "$kind" = fixed ] || method=seq
  local dump=$WORK/acc-$kind-$bits.primary.csv
  if ! "$ZEPHYR" render --method $method --scene "$acc_scene" --report "$rj" --no-progress \
       --dump-primary "$dump" "$@" \
       >"$WORK/last.log" 2>&1; then
    say "failed: render --method $method $*"; tail -n 5 "$WORK/last.log" >&2; return 0
  fi
  local cycles host acc="NaN,NaN,NaN,NaN"
  cycles=$(jq -r "$JQ_CYCLES" "$rj"); [ "$cycles" = null ] && cycles=NaN
  host=$(jq -r '.phases.render' "$rj")
  if has_command accuracy && "$ZEPHYR" accuracy --method $method --scene "$acc_scene" --report "$aj" "$@" \
       >"$WORK/last.log" 2>&1; then
    acc=$(jq -r "$JQ_ACC" "$aj")
  elif [ -f "$ACC_REF" ]; then
    # Until `zephyr accuracy` exists: compare the primary hits (--dump-primary CSV, a data
    # file) with the float64 sequential tracer's. PSNR needs the exact reference image.
    acc=$(awk -F, 'NR == FNR { if (FNR > 1) { o[FNR] = $6; t[FNR] = $7 } next }
      FNR > 1 { ++n; if ($6 != o[FNR]) ++wrong
                else if ($6 >= 0) { e = $7 - t[FNR]; e = e < 0 ? -e : e; s += e; ++m; if (e > mx) mx = e } }
      END { printf "%.6g,%.6g,%.6g,NaN", 100 * wrong / n, mx, m ? s / m : 0 }' "$ACC_REF" "$dump")
  else
    say "no accuracy figures for $kind $bits"
  fi
  echo "$kind,$bits,$cycles,$host,$acc,$planned" >>"$ACC"
  [ "$kind" = fixed ] && [ "$planned" = 0 ] && echo "$bits,$(jq -r "$JQ_UNC" "$rj")" >>"$UNC"
  return 0
}

ACC_NOTE="$REF_COUNT random spheres, ${SIZE}x${SIZE}; labels = fraction bits"
# The reference primary hits for the fallback comparison: the float64 sequential tracer.
ACC_REF=$WORK/acc-reference.primary.csv
"$ZEPHYR" render --method seq --precision double --scene "$acc_scene" --no-progress \
  --dump-primary "$ACC_REF" >/dev/null 2>&1 || rm -f "$ACC_REF"
has_command accuracy || ACC_NOTE="reference: seq float64 primary hits (zephyr accuracy not available yet; no PSNR). $ACC_NOTE"
if has_method simd; then
  for bits in $FRAC; do accuracy_row fixed "$bits" 0 --frac-bits "$bits"; done
  accuracy_row fixed planned 1
else
  skip "speed vs accuracy sweep (needs render --method simd)"
  ACC_NOTE="SIMD method not available yet (skipped). $ACC_NOTE"
fi
if has_method seq; then
  accuracy_row float32 NaN 0 --precision float
  accuracy_row float64 NaN 0 --precision double
fi
# The planner's row has no numeric width in the CSV: label it by the width it chose, if known.
sed -i 's/^fixed,planned,/fixed,NaN,/' "$ACC"

for spec in "5:pct_wrong:% of pixels with a wrong first object:0" \
            "6:t_error:max error in t (scene units):1" \
            "8:psnr:PSNR of the image against the exact reference (dB):0"; do
  IFS=: read -r xcol tag xl logx <<<"$spec"
  acc_empty=1  # no measured point on this accuracy axis (a log axis needs one above 0)
  awk -F, -v c="$xcol" -v lg="$logx" 'NR > 1 && $c != "NaN" && (!lg || $c > 0) { f = 1 } END { exit !f }' "$ACC" \
    && acc_empty=0
  gnuplot -e "in='$ACC'; out='$OUT/speed_vs_accuracy_$tag.png'; xcol=$xcol; logx=$logx; \
ttl='Speed against accuracy: $xl'; xl='$xl'; note='$ACC_NOTE'; empty=$acc_empty" "$GP/accuracy.gp"
  say "wrote $OUT/speed_vs_accuracy_$tag.png"
done
chart uncertain_pixels "Uncertain pixels the SIMD pass detects, by fraction width" \
  "fraction bits (--frac-bits)" "pixels" 0 0 "$(note_for simd) $ACC_NOTE" \
  "overflow / grazing (discriminant within the error bound of 0) / near tie (two t within the bound)"
