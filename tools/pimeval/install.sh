#!/usr/bin/env bash
# tools/pimeval/install.sh ROOT PREFIX LIST ARCHIVE — the PIMeval API's part of `make install`
# (docs/pim.md): ROOT/include/libpimeval.h, ROOT/lib/libzephyr-pimeval.a (the API and the
# engine's objects) and ROOT/lib/libpimeval.a, a GNU ld script naming that archive by its
# final path PREFIX/lib/... and the shared libraries the engine needs (Highway, fmt, libgomp:
# Debian ships Highway as a shared library only), so that PIMbench's link line
# `g++ prog.cpp -std=c++17 -I.../include -L.../lib -lpimeval` links as it stands. ROOT is
# PREFIX under DESTDIR; each installed path (relative to ROOT) is appended to LIST, which
# `make uninstall` reads.
set -euo pipefail
if [ $# -ne 4 ]; then echo "usage: $0 ROOT PREFIX LIST ARCHIVE" >&2; exit 2; fi
root=$1 prefix=$2 list=$3 archive=$4
here=$(cd "$(dirname "$0")" && pwd)
[ -f "$archive" ] || { echo "install.sh: $archive not found (make pimeval-lib)" >&2; exit 1; }
[ -f "$list" ] || { echo "install.sh: the installed-files list $list not found" >&2; exit 1; }
libs=$(pkg-config --libs libhwy fmt)
install -D -m 644 "$here/libpimeval.h" "$root/include/libpimeval.h"
install -D -m 644 "$archive" "$root/lib/libzephyr-pimeval.a"
script=$(mktemp)
{
  echo "/* GNU ld script: PIMeval's host API on the emulated Zephyr (docs/pim.md). */"
  echo "INPUT($prefix/lib/libzephyr-pimeval.a $libs -lgomp -lpthread)"
} > "$script"
install -m 644 "$script" "$root/lib/libpimeval.a"
rm -f "$script"
printf '%s\n' include/libpimeval.h lib/libzephyr-pimeval.a lib/libpimeval.a >> "$list"
echo "installed PIMeval's API: $root/include/libpimeval.h, $root/lib/libpimeval.a (-lpimeval)"
