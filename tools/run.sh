#!/usr/bin/env bash
# `make run`: render SCENE (or a generated random-sphere scene) with METHOD and print the
# cycle report. Grows as the methods land (see docs/architecture.md).
set -euo pipefail
ZEPHYR=build/bin/zephyr
mkdir -p out
if [ -z "${SCENE:-}" ]; then
  SCENE=out/spheres-${SPHERES}-seed${SEED}.nff
  if ! $ZEPHYR gen spheres --count "$SPHERES" --seed "$SEED" --out "$SCENE" 2>/dev/null; then
    echo "make run: not yet — the scene generator (issue 4) has not landed." >&2
    exit 2
  fi
fi
name=$(basename "${SCENE%.*}")
exec $ZEPHYR render --method "$METHOD" --scene "$SCENE" --out "out/$name.png" \
  --report "out/$name.json"
