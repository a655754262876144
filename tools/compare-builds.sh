#!/usr/bin/env bash
# Compares the outputs of two zephyr builds: the PNG, the --dump-primary CSV and the JSON
# report of seq, simd, dist and hetero on the generated scenes (spheres, flake, showcase)
# and every NFF scene in SCENES (default: the SPD samples in tests/fuzz/corpus; point it at a
# folder of Eric Haines' SPD scenes for more), all at 128×128.
#
#   [SCENES=DIR] tools/compare-builds.sh OLD/zephyr NEW/zephyr [WORKDIR]
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
normalise() {
  jq -S 'walk(if type == "object" then with_entries(select(.key
           | test("[Ss]econds|^perChild$|^phases$|^pid$|^host$|[Rr]ealTime") | not)) else . end)
         | del(.distributed.traffic.childrenToParent.stats?,
               .distributed.traffic.childrenToParent.ready.payloadBytes?,
               .distributed.traffic.childrenToParent.total.payloadBytes?)' "$1"
}

run() {  # run BIN OUTDIR SCENE METHOD
  local bin=$1 dir=$2 scene=$3 method=$4 name
  name=$(basename "$scene" .nff).$method
  local args=(render --method "$method" "$scene" --out "$dir/$name.png" --report "$dir/$name.json"
              --no-progress)
  case $method in  # dist and hetero produce no --dump-primary (it is an error there)
    seq|simd) args+=(--dump-primary "$dir/$name.csv") ;;
  esac
  case $method in
    dist|hetero) mpirun --oversubscribe -np 3 "$bin" "${args[@]}" --frame 32 >/dev/null 2>"$dir/$name.err" ;;
    *) "$bin" "${args[@]}" >/dev/null 2>"$dir/$name.err" ;;
  esac
  echo $? > "$dir/$name.rc"
}

same=0; diff=0
for scene in "$work"/scenes/*.nff; do
  for method in seq simd dist hetero; do
    run "$old" "$work/old" "$scene" "$method"
    run "$new" "$work/new" "$scene" "$method"
    name=$(basename "$scene" .nff).$method
    for ext in rc png csv json; do
      a="$work/old/$name.$ext" b="$work/new/$name.$ext"
      [ -e "$a" ] || [ -e "$b" ] || continue
      if [ "$ext" = json ]; then
        cmp -s <(normalise "$a" 2>/dev/null) <(normalise "$b" 2>/dev/null); r=$?
      else
        cmp -s "$a" "$b"; r=$?
      fi
      if [ $r -eq 0 ]; then same=$((same + 1)); echo "same      $name.$ext"
      else diff=$((diff + 1)); echo "DIFFERENT $name.$ext"; fi
    done
  done
done
echo "compare-builds: $same identical, $diff different (outputs in $work)"
[ $diff -eq 0 ]
