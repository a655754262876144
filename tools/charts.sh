#!/usr/bin/env bash
# `make charts`: the experiment sweeps and charts (issue 7).
echo "make charts: not yet — the sweeps and charts land with issue 7." >&2
exit 2
