#!/usr/bin/env bash
# `make run`: render SCENE (or a generated random-sphere scene) with METHOD and print the
# cycle report. dist and hetero run under mpirun with WORKERS children (ranks = WORKERS+1)
# and FRAME×FRAME frames: oversubscribed when the ranks outnumber the cores, allowed to run
# as root (containers). RESUME=1 renders only the frames missing from out/NAME.png.frames.
set -euo pipefail
ZEPHYR=${ZEPHYR:-build/bin/zephyr}
mkdir -p out
if [ -z "${SCENE:-}" ]; then
  SCENE=out/spheres-${SPHERES}-seed${SEED}.nff
  if ! $ZEPHYR gen spheres --count "$SPHERES" --seed "$SEED" --out "$SCENE" 2>/dev/null; then
    echo "make run: could not generate $SCENE (run: $ZEPHYR gen spheres --count $SPHERES --seed $SEED)" >&2
    exit 2
  fi
fi
name=$(basename "${SCENE%.*}")
args=(render --method "$METHOD" --scene "$SCENE" --out "out/$name.png" --report "out/$name.json")
case "$METHOD" in
  dist|hetero)
    WORKERS=${WORKERS:-2}
    FRAME=${FRAME:-64}
    if ! [[ "$WORKERS" =~ ^[0-9]+$ ]] || [ "$WORKERS" -lt 1 ]; then
      echo "make run: WORKERS must be a whole number ≥ 1 (the children; got '$WORKERS')" >&2
      exit 2
    fi
    ranks=$((WORKERS + 1))
    mpi=(mpirun -np "$ranks")
    [ "$ranks" -gt "$(nproc)" ] && mpi+=(--oversubscribe)
    [ "$(id -u)" = 0 ] && mpi+=(--allow-run-as-root)
    args+=(--frame "$FRAME")
    [ -n "${RESUME:-}" ] && args+=(--resume)
    exec "${mpi[@]}" "$ZEPHYR" "${args[@]}"
    ;;
  *)
    exec $ZEPHYR "${args[@]}"
    ;;
esac
