#!/usr/bin/env bash
# tools/testbed/simrun.sh — run build/bin/zephyr-smpi under SimGrid's smpirun on a testbed
# platform (docs/testbed.md): rank 0 on the host "parent", rank i on the i-th child host.
#
#   tools/testbed/simrun.sh --children K [--testbed NAME|FILE] [--platform FILE] [--hostfile FILE] \
#       [--zephyr PATH] [--cfg NAME:VALUE ...] -- render --method dist|hetero SCENE --testbed ufmg1992 --out x.png --report r.json
#
# Without --platform the named testbed's platform (--testbed, default ufmg1992) with K
# children is written by `zephyr testbed platform` (from the host profiles); --testbed FILE
# (a path to an existing file) is the same as --platform FILE. With --platform FILE the hosts are
# taken from it (or from --hostfile): a malformed file or too few hosts is an error naming
# the file. --children 0 runs seq or simd alone on the parent host (their work charged to
# it, simd's array cycles to the platform's array host). Computation is never measured (smpi/simulate-computation:no): the children
# charge their counted work; SimGrid's network factors are 1 (the link figures as given).
# --cfg NAME:VALUE (repeatable) passes one more SimGrid setting to smpirun, after these
# (e.g. --cfg network/crosstraffic:no; docs/testbed.md, "Bytes on the Ethernet").
set -euo pipefail

children="" platform="" hostfile="" zephyr="" testbed="ufmg1992" extra=()
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# An option's value: present and not empty, else a message naming the option.
value() {
  [[ $# -ge 2 && -n "$2" && "$2" != --* ]] ||
    { echo "simrun.sh: $1 needs a value (see the header of $0)" >&2; exit 2; }
  printf '%s' "$2"
}
while [[ $# -gt 0 ]]; do
  case "$1" in
    --children) children="$(value "$@")"; shift 2 ;;
    --platform) platform="$(value "$@")"; shift 2 ;;
    --testbed) v="$(value "$@")"; if [[ "$v" == */* || -e "$v" ]]; then platform="$v"; else testbed="$v"; fi; shift 2 ;;
    --hostfile) hostfile="$(value "$@")"; shift 2 ;;
    --zephyr) zephyr="$(value "$@")"; shift 2 ;;
    --cfg) extra+=("--cfg=$(value "$@")"); shift 2 ;;
    --) shift; break ;;
    *) echo "simrun.sh: unknown option '$1' (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ "$children" =~ ^(0|[1-9][0-9]*)$ ]] ||
  { echo "simrun.sh: --children K (K >= 1 for dist/hetero; 0 for seq/simd, the parent alone) is required" >&2; exit 2; }
# The method the render runs must match the children: dist and hetero farm frames to K >= 1
# children; every other method runs on the parent alone (with K children it would run K + 1
# times, each rank writing the same files).
method="" prev=""
for a in "$@"; do
  [[ "$prev" == --method ]] && method="$a"
  [[ "$a" == --method=* ]] && method="${a#--method=}"
  prev="$a"
done
if [[ "$method" == dist || "$method" == hetero ]]; then
  (( children >= 1 )) || { echo "simrun.sh: --method $method needs --children K >= 1" >&2; exit 2; }
elif [[ -n "$method" ]] && (( children != 0 )); then
  echo "simrun.sh: --method $method runs on the parent alone: give --children 0 (not $children)" >&2; exit 2
fi
zephyr="${zephyr:-$here/build/bin/zephyr-smpi}"
[[ -f "$zephyr" ]] || { echo "simrun.sh: $zephyr not found: build it with \`make smpi\`" >&2; exit 2; }
command -v smpirun >/dev/null || { echo "simrun.sh: smpirun not found (Debian package simgrid; tools/setup.sh)" >&2; exit 2; }

tmp="$(mktemp -d)"
# Removed on every way out: the end, an error, and SIGINT/SIGTERM/SIGHUP (smpirun is not
# exec'd, so this shell is still there to clean up).
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP
if [[ -z "$platform" ]]; then
  platform="$tmp/ufmg1992.xml"
  "$(dirname "$zephyr")/zephyr" testbed platform --testbed "$testbed" --children "$(( children > 0 ? children : 1 ))" --out "$platform" \
    --hostfile "$tmp/hosts"
  hostfile="${hostfile:-$tmp/hosts}"
else
  # A regular, readable file only: a FIFO would block xmllint and smpirun for ever.
  [[ -f "$platform" && -r "$platform" ]] ||
    { echo "$platform: cannot read the platform file (no such file, or not a regular file)" >&2; exit 2; }
  if ! err="$(xmllint --noout "$platform" 2>&1)"; then
    echo "$platform: not a well-formed platform file:" >&2
    echo "$err" | head -n 5 >&2
    exit 2
  fi
  # SimGrid aborts on a host of speed 0 or a link of 0 bit/s (and the render would leave an
  # empty checkpoint): refused here, naming the element.
  for xp in '//host/@speed' '//link/@bandwidth' '//cluster/@speed' '//cluster/@bw'; do
    while read -r v; do
      [[ -z "$v" ]] && continue
      n="${v%%[!0-9.eE+-]*}"
      if [[ -z "$n" ]] || ! awk -v x="$n" 'BEGIN { exit !(x + 0 > 0) }'; then
        echo "$platform: ${xp#//} '$v' is not above zero (SimGrid needs every host speed and link bandwidth > 0)" >&2
        exit 2
      fi
    done < <(xmllint --xpath "$xp" "$platform" 2>/dev/null | grep -o '"[^"]*"' | tr -d '"')
  done
  if [[ -z "$hostfile" ]]; then
    # Every host of the file but the array, in file order: the first is the parent.
    xmllint --xpath '//host[not(prop[@id="zephyr:role" and @value="array"])]/@id' "$platform" \
      2>/dev/null | grep -o 'id="[^"]*"' | sed 's/^id="\(.*\)"$/\1/' > "$tmp/hosts" || true
    hostfile="$tmp/hosts"
    source_name="$platform"
  fi
fi
source_name="${source_name:-$hostfile}"
have=$(grep -c . "$hostfile" || true)
if (( have < children + 1 )); then
  echo "$source_name: $have host(s) for the parent and $children children; $((children + 1)) needed" >&2
  exit 2
fi

smpirun -np "$((children + 1))" -platform "$platform" -hostfile "$hostfile" \
  --cfg=smpi/simulate-computation:no --cfg=smpi/bw-factor:0:1 --cfg=smpi/lat-factor:0:1 \
  --cfg=smpi/display-timing:no --cfg=plugin:link_load --log=root.thres:warning "${extra[@]}" \
  "$zephyr" "$@" && status=0 || status=$?
exit "$status"
