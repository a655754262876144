#!/usr/bin/env bash
# Compares the outputs of two zephyr builds: the PNG, the --dump-primary CSV and the JSON
# report of seq, simd, dist and hetero on the generated scenes (spheres, flake, showcase)
# and every NFF scene in SCENES (default: the SPD samples in tests/fuzz/corpus; point it at a
# folder of Eric Haines' SPD scenes for more), all at 128×128.
#
#   [SCENES=DIR] [OLD_JQ=FILTER] [BOTH_JQ=FILTER] tools/compare-builds.sh OLD/zephyr NEW/zephyr [WORKDIR]
#
# seq and simd run a second time with --testbed ufmg1992 (the modelled seconds), seq and
# hetero a third with --accel bvh on it (the hierarchy's counted work); array (every ray on
# the array) with its default compaction, and with --compact mesh on it; each run's
# standard output (the cycle report, the summary line) is compared too, with its wall-clock
# figures blanked. OLD_JQ is a jq filter applied to the old build's reports first: a change
# that renames report keys lists the renames there (docs/report.md lists them); BOTH_JQ is
# applied to both builds' reports, for a section a change alters on purpose (e.g.
# 'del(.simd.plan.formats)' when the plan's table changes).
#
# Used to show that a change which should not change behaviour (a re-layout, a speed-up)
# does not: every PNG and CSV must be byte-identical, and every report identical once the
# figures that differ from run to run by nature are removed (wall-clock seconds, process
# ids and host names, and which child happened to take which frame). Prints one line per
# comparison and "compare-builds: N identical, N different"; exits 1 if any differ.
set -uo pipefail

old=${1:?usage: tools/compare-builds.sh OLD_ZEPHYR NEW_ZEPHYR [WORKDIR]}
new=${2:?usage: tools/compare-builds.sh OLD_ZEPHYR NEW_ZEPHYR [WORKDIR]}
work=${3:-$(mktemp -d)}
mkdir -p "$work/scenes" "$work/old" "$work/new"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
here=$(cd "$(dirname "$0")/.." && pwd)

# Scenes: the generators of the OLD build (so both builds read the same files).
"$old" gen spheres --count 16 --seed 1 --size 128x128 --out "$work/scenes/spheres.nff"
"$old" gen flake --depth 3 --size 128x128 --out "$work/scenes/flake.nff"
"$old" gen showcase --size 128x128 --out "$work/scenes/showcase.nff"
scenes=${SCENES:-$here/tests/fuzz/corpus}
if [ -d "$scenes" ]; then
  for f in "$scenes"/*.nff; do
    [ -e "$work/scenes/$(basename "$f")" ] && continue  # a generated scene of that name
    sed 's/^resolution .*/resolution 128 128/' "$f" > "$work/scenes/$(basename "$f")"
  done
fi

# Removes what differs between two runs of the same build. Each child's ready message
# carries its process id and its stats message its timings, as text: their sizes vary.
normalise() {  # normalise REPORT [JQ_FILTER]
  jq -S "${2:-.}"' | walk(if type == "object" then with_entries(select(.key
           | test("[Ss]econds|^perChild$|^phases$|^pid$|^host$|[Rr]ealTime") | not)) else . end)
         | del(.distributed.traffic.childrenToParent.stats?,
               .distributed.traffic.childrenToParent.ready.payloadBytes?,
               .distributed.traffic.childrenToParent.total.payloadBytes?)' "$1"
}

# The wall-clock figures of the cycle report and the summary line, the output folder, and
# the bytes the children sent back (their stats messages carry timings as text).
untimed() {
  sed -E "s/host time [0-9.e+-]+ s; real-time factor [0-9.e+infa-]+/host time T/; s/rendered in [0-9.]+ s/rendered in T s/;
          s#$work/(old|new)/#OUT/#g; s/[0-9]+ back\$/N back/" "$1"
}

run() {  # run BIN OUTDIR SCENE METHOD [SUFFIX FLAG...]: SUFFIX names the run's flags
  local bin=$1 dir=$2 scene=$3 method=$4 suffix=${5:-} name
  shift 5 2>/dev/null || shift 4
  name=$(basename "$scene" .nff).$method${suffix:+.$suffix}
  local args=(render --method "$method" "$scene" --out "$dir/$name.png" --report "$dir/$name.json"
              --no-progress "$@")
  case $method in  # dist and hetero produce no --dump-primary (it is an error there)
    seq|simd) args+=(--dump-primary "$dir/$name.csv") ;;
  esac
  case $method in
    dist|hetero) mpirun --oversubscribe -np 3 "$bin" "${args[@]}" --frame 32 >"$dir/$name.out" 2>"$dir/$name.err" ;;
    *) "$bin" "${args[@]}" >"$dir/$name.out" 2>"$dir/$name.err" ;;
  esac
  echo $? > "$dir/$name.rc"
}

same=0; diff=0
compare() {  # compare NAME: every output of one run of both builds
  local name=$1 ext a b r
  for ext in rc png csv json out; do
    a="$work/old/$name.$ext" b="$work/new/$name.$ext"
    [ -e "$a" ] || [ -e "$b" ] || continue
    case $ext in
      json) cmp -s <(normalise "$a" "${OLD_JQ:-.} | ${BOTH_JQ:-.}" 2>/dev/null) \
                   <(normalise "$b" "${BOTH_JQ:-.}" 2>/dev/null); r=$? ;;
      out) cmp -s <(untimed "$a") <(untimed "$b"); r=$? ;;
      *) cmp -s "$a" "$b"; r=$? ;;
    esac
    if [ $r -eq 0 ]; then same=$((same + 1)); echo "same      $name.$ext"
    else diff=$((diff + 1)); echo "DIFFERENT $name.$ext"; fi
  done
}

for scene in "$work"/scenes/*.nff; do
  base=$(basename "$scene" .nff)
  for method in seq simd dist hetero; do
    run "$old" "$work/old" "$scene" "$method"
    run "$new" "$work/new" "$scene" "$method"
    compare "$base.$method"
  done
  for method in seq simd; do
    run "$old" "$work/old" "$scene" "$method" ufmg1992 --testbed ufmg1992
    run "$new" "$work/new" "$scene" "$method" ufmg1992 --testbed ufmg1992
    compare "$base.$method.ufmg1992"
  done
  # The host tracer's hierarchy: its walk's counted work (node visits, box tests, tests by
  # kind) at the parent and at the children, priced.
  for method in seq hetero; do
    run "$old" "$work/old" "$scene" "$method" bvh --accel bvh --testbed ufmg1992
    run "$new" "$work/new" "$scene" "$method" bvh --accel bvh --testbed ufmg1992
    compare "$base.$method.bvh"
  done
  # Every ray on the array (the wavefront): its bounces' cycles under both compactions.
  run "$old" "$work/old" "$scene" array ""
  run "$new" "$work/new" "$scene" array ""
  compare "$base.array"
  run "$old" "$work/old" "$scene" array mesh --compact mesh --testbed ufmg1992
  run "$new" "$work/new" "$scene" array mesh --compact mesh --testbed ufmg1992
  compare "$base.array.mesh"
done
echo "compare-builds: $same identical, $diff different (outputs in $work)"
[ $diff -eq 0 ]
