# tools/testbed/sweep.sh — what the modelled sweeps share (sourced by tools/testbed/charts.sh
# and tools/testbed/future.sh; docs/testbed.md): the checks before any render, the scratch
# folder, the scenes. The caller sets ROOT, ZEPHYR, ZEPHYR_SMPI, OUT, SIZE, SEED and NAME (its
# name in messages) before sourcing; afterwards WORK is a scratch folder removed at exit.

say() { echo "$NAME: $*" >&2; }
for tool in jq gnuplot awk xmllint; do
  command -v "$tool" >/dev/null || { say "$tool not found (run tools/setup.sh)"; exit 1; }
done
[ -x "$ZEPHYR" ] || { say "$ZEPHYR not built (make)"; exit 1; }
[ -f "$ZEPHYR_SMPI" ] || { say "$ZEPHYR_SMPI not built (make smpi)"; exit 1; }
mkdir -p "$OUT"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/zephyr-sweep.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
# scene N: the random-sphere scene of N objects (SIZE × SIZE, SEED); make_scenes N...: writes
# each once.
scene() { echo "$WORK/spheres-$1.nff"; }
make_scenes() {
  for n in "$@"; do
    [ -f "$(scene "$n")" ] || "$ZEPHYR" gen spheres --count "$n" --seed "$SEED" --size "${SIZE}x${SIZE}" --out "$(scene "$n")"
  done
}
