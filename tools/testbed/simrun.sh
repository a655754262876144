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
while [[ $# -gt 0 ]]; do
  case "$1" in
    --children) children="$2"; shift 2 ;;
    --platform) platform="$2"; shift 2 ;;
    --testbed) if [[ "$2" == */* || -f "$2" ]]; then platform="$2"; else testbed="$2"; fi; shift 2 ;;
    --hostfile) hostfile="$2"; shift 2 ;;
    --zephyr) zephyr="$2"; shift 2 ;;
    --cfg) extra+=("--cfg=$2"); shift 2 ;;
    --) shift; break ;;
    *) echo "simrun.sh: unknown option '$1' (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ "$children" =~ ^(0|[1-9][0-9]*)$ ]] ||
  { echo "simrun.sh: --children K (K >= 1 for dist/hetero; 0 for seq/simd, the parent alone) is required" >&2; exit 2; }
zephyr="${zephyr:-$here/build/bin/zephyr-smpi}"
[[ -f "$zephyr" ]] || { echo "simrun.sh: $zephyr not found: build it with \`make smpi\`" >&2; exit 2; }
command -v smpirun >/dev/null || { echo "simrun.sh: smpirun not found (Debian package simgrid; tools/setup.sh)" >&2; exit 2; }

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
if [[ -z "$platform" ]]; then
  platform="$tmp/ufmg1992.xml"
  "$(dirname "$zephyr")/zephyr" testbed platform --testbed "$testbed" --children "$(( children > 0 ? children : 1 ))" --out "$platform" \
    --hostfile "$tmp/hosts"
  hostfile="${hostfile:-$tmp/hosts}"
else
  [[ -r "$platform" ]] || { echo "$platform: cannot read the platform file" >&2; exit 2; }
  if ! err="$(xmllint --noout "$platform" 2>&1)"; then
    echo "$platform: not a well-formed platform file:" >&2
    echo "$err" | head -n 5 >&2
    exit 2
  fi
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

exec smpirun -np "$((children + 1))" -platform "$platform" -hostfile "$hostfile" \
  --cfg=smpi/simulate-computation:no --cfg=smpi/bw-factor:0:1 --cfg=smpi/lat-factor:0:1 \
  --cfg=smpi/display-timing:no --cfg=plugin:link_load --log=root.thres:warning "${extra[@]}" \
  "$zephyr" "$@"
