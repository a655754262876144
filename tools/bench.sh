#!/usr/bin/env bash
# `make bench`: run every benchmark program given on the command line, one after another
# (never two at once: they time themselves). Each prints its own figures.
set -uo pipefail
if [ $# -eq 0 ]; then
  echo "make bench: no benchmark programs given (tools/bench/*.cpp builds one each)."
  exit 0
fi
status=0
for b in "$@"; do
  echo "=== $(basename "$b") ==="
  "$b" || status=1
done
exit $status
