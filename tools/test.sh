#!/usr/bin/env bash
# `make test`: run the GoogleTest binary and end with its summary line followed by a plain
# "N passed, N failed" line (counted from GoogleTest's XML), so any reader of the log sees
# the outcome. Usage: tools/test.sh TEST_BINARY [gtest flags...]
set -uo pipefail
bin=$1; shift
xml=$(dirname "$bin")/../test_results.xml
rm -f "$xml"
"$bin" --gtest_brief=1 --gtest_output="xml:$xml" "$@"
status=$?
if [ -f "$xml" ]; then
  # The root <testsuites> element carries the totals.
  root=$(grep -m1 '<testsuites ' "$xml")
  total=$(sed -n 's/.* tests="\([0-9]*\)".*/\1/p' <<<"$root")
  failed=$(sed -n 's/.* failures="\([0-9]*\)".*/\1/p' <<<"$root")
  disabled=$(sed -n 's/.* disabled="\([0-9]*\)".*/\1/p' <<<"$root")
  skipped=$(grep -c '<skipped' "$xml" || true)
  run=$(( total - ${disabled:-0} ))
  echo "tests: $(( run - failed - skipped )) passed, $failed failed, $skipped skipped"
else
  echo "tests: 0 passed, 1 failed (the test binary wrote no results)"
  [ $status -eq 0 ] && status=1
fi
exit $status
