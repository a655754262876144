#!/usr/bin/env bash
# tools/validate.sh — `make validate` (docs/validation.md): the fidelity ledger. The paper rows
# read the testbed sweep's runs.csv; the sweep is run first with REUSE=1 (only the points the
# file lacks are rendered: the model is deterministic, so a point once rendered stays until the
# code changes; FRESH=1 renders every point again). Then the ledger, its CSV and its chart.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
ZEPHYR=${ZEPHYR:-build/bin/zephyr}
RUNS=docs/results/testbed-ufmg1992/runs.csv
if [ "${FRESH:-0}" != 0 ]; then rm -f "$RUNS"; fi
REUSE=1 TESTBED=ufmg1992 bash tools/testbed/charts.sh
"$ZEPHYR" validate --runs "$RUNS" --out docs/validation.md --csv docs/results/validation.csv \
  --check tools/validation_recorded.csv
# Model against published on log axes, the y = x line: the rate rows (bounds drawn apart).
gnuplot <<'GP'
set terminal pngcairo size 800,700 font ',10'
set output 'docs/results/validation.png'
set datafile separator ','
set title 'Fidelity ledger: the model against published rates (docs/validation.md)'
set xlabel 'published (MOPS / MFLOPS)'
set ylabel 'model (MOPS / MFLOPS)'
set logscale xy
set grid
set key top left box opaque
set xrange [100:10000]
set yrange [100:10000]
plot x with lines dt 2 lc rgb '#888888' title 'y = x', \
  'docs/results/validation.csv' using ((strcol(1) eq 'mpp' && strcol(3) eq 'rate') ? $4 : NaN):6 with points pt 7 ps 1.5 title 'MPP (Batcher 1980)', \
  '' using ((strcol(1) eq 'blitzen') ? $4 : NaN):6 with points pt 9 ps 1.8 title 'BLITZEN lower bounds (Blevins et al. 1990)'
GP
echo "validate: wrote docs/validation.md, docs/results/validation.csv, docs/results/validation.png"
