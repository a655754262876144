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
# Model against published on log axes, the y = x line: every row with a published number
# (rates, times, bounds; the paper's checks have none), each machine in its own colour. The
# machines are the CSV's own (first column), so a machine added to the ledger is drawn without
# touching this script; a lower bound is drawn as a triangle (a point type of its own: the
# key shows each machine's colour with a dot, which `pt variable` left blank).
CSV=docs/results/validation.csv
MACHINES=$(awk -F, 'NR > 1 && $3 != "check" && !seen[$1]++ { printf "%s ", $1 }' "$CSV")
gnuplot <<GP
set terminal pngcairo size 800,700 font ',10'
set output 'docs/results/validation.png'
set datafile separator ','
set title 'Fidelity ledger: the model against published figures (docs/validation.md)'
set xlabel 'published (each row in its own unit: MOPS, MFLOPS, s, us, tCK)'
set ylabel 'model (the same unit)'
set logscale xy
set grid
set key top left box opaque
set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
machines = "$MACHINES"
plot x with lines dt 2 lc rgb '#888888' title 'y = x', \
  for [i=1:words(machines)] '$CSV' \
    using ((strcol(1) eq word(machines, i) && strcol(3) ne 'lower bound') ? \$4 : NaN):6 \
    with points pt 7 ps 1.5 lc i title word(machines, i), \
  for [i=1:words(machines)] '$CSV' \
    using ((strcol(1) eq word(machines, i) && strcol(3) eq 'lower bound') ? \$4 : NaN):6 \
    with points pt 9 ps 1.5 lc i notitle
GP
echo "validate: wrote docs/validation.md, docs/results/validation.csv, docs/results/validation.png"
