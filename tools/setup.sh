#!/usr/bin/env bash
# Installs the Debian packages the build, tests, benchmarks and charts need — only the
# missing ones, with at most one `apt-get update`. Costs one dpkg-query when all are there.
# Called by the Makefile before every build target; safe to run by hand.
set -euo pipefail

PACKAGES=(
  g++ make pkg-config ccache   # ccache: a rebuild after an edit or a rebase (issue 41)
  libhwy-dev libboost-dev libpng-dev libgtest-dev
  libopenmpi-dev openmpi-bin
  libcli11-dev nlohmann-json3-dev libfmt-dev
  clang libclang-rt-14-dev   # libFuzzer + sanitizers for `make fuzz`
  povray                     # independent reference renderer (docs/background.md)
  libembree-dev              # outside speed reference in `make bench` (docs/background.md)
  gnuplot-nox jq             # `make charts` (tools/charts.sh: bash + jq + gnuplot, no Python)
  simgrid libsimgrid-dev libxml2-utils  # `make smpi`: the 1992 testbed under SMPI (docs/testbed.md)
)

missing=()
status=$(dpkg-query -W -f='${Package} ${db:Status-Abbrev}\n' "${PACKAGES[@]}" 2>/dev/null || true)
for p in "${PACKAGES[@]}"; do
  if ! grep -q "^${p} ii" <<<"$status"; then missing+=("$p"); fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "setup: installing missing Debian packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done" >&2
