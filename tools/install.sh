#!/usr/bin/env bash
# tools/install.sh — what `make install` and `make uninstall` run (docs/programming.md,
# "Building a program on the library").
#
#   PREFIX=/usr/local [DESTDIR=/stage] tools/install.sh install   (the files: from the environment)
#   PREFIX=/usr/local [DESTDIR=/stage] tools/install.sh uninstall
#
# PREFIX and DESTDIR come from the environment as the user typed them (make exports them), so
# a prefix with spaces or quotes is one path, never split or re-parsed by a shell. PREFIX must
# be an absolute path; DESTDIR, when given, too. Install stages every file in a temporary
# folder beside the destination and moves the files in only when all are staged: a failed
# install leaves nothing (no file, no list, no temporary). The list of what was installed
# (share/zephyr/installed-files, one path relative to the prefix a line) is written last;
# uninstall removes only the list's regular files that lie under the prefix (a line with an
# absolute path, a '..' component or a newline trick is refused, the file is left).
#
# install's inputs (set by the Makefile): LIB_A (the archive), LIB_NAME, PUBLIC_HEADERS,
# PROFILE_FILES (space-separated repository paths, no spaces), PC_REQUIRES, LIB_VERSION,
# and EXTRA_INSTALL: more "SOURCE=DEST" pairs (DEST relative to the prefix), space-separated.
set -euo pipefail

mode="${1:-}"
[[ "$mode" == install || "$mode" == uninstall ]] ||
  { echo "install.sh: expected 'install' or 'uninstall', got '$mode'" >&2; exit 2; }
prefix="${PREFIX-}"
destdir="${DESTDIR-}"
[[ -n "$prefix" ]] ||
  { echo "$mode: PREFIX is empty: give an absolute path, e.g. PREFIX=/usr/local" >&2; exit 2; }
[[ "$prefix" == /* ]] ||
  { echo "$mode: PREFIX '$prefix' is not an absolute path (e.g. PREFIX=\$PWD/$prefix)" >&2; exit 2; }
[[ -z "$destdir" || "$destdir" == /* ]] ||
  { echo "$mode: DESTDIR '$destdir' is not an absolute path" >&2; exit 2; }
[[ "$prefix$destdir" != *$'\n'* ]] ||
  { echo "$mode: PREFIX and DESTDIR may not hold a newline" >&2; exit 2; }
# The prefix as the installed files name it: '.', '..' and repeated '/' resolved lexically
# (the folder may not exist yet), never '/' alone.
prefix="$(realpath -m -- "$prefix")"
[[ "$prefix" != / ]] ||
  { echo "$mode: PREFIX '/' would install into the root: give a folder, e.g. PREFIX=/usr/local" >&2; exit 2; }
root="${destdir:+$(realpath -m -- "$destdir")}$prefix"
list_rel="share/zephyr/installed-files"
list="$root/$list_rel"

if [[ "$mode" == uninstall ]]; then
  [[ -f "$list" ]] ||
    { echo "uninstall: nothing installed under $root ($list not found)" >&2; exit 1; }
  refused=0
  while IFS= read -r f || [[ -n "$f" ]]; do
    [[ -z "$f" ]] && continue
    # Only a relative path under the prefix: no leading '/', no '..' component.
    if [[ "$f" == /* || "/$f/" == */../* || "/$f/" == */./* ]]; then
      echo "uninstall: $list: '$f' is not a path under the prefix: left alone" >&2
      refused=1
      continue
    fi
    if [[ -f "$root/$f" || -L "$root/$f" ]]; then rm -f -- "$root/$f"; fi
  done < "$list"
  rm -f -- "$list"
  for d in include/zephyr/fixed include/zephyr/bitserial include/zephyr share/zephyr/profiles \
           share/zephyr lib/pkgconfig; do
    rmdir -- "$root/$d" 2>/dev/null || true
  done
  echo "removed the installed files under $root"
  exit "$refused"
fi

: "${LIB_A:?}" "${LIB_NAME:?}" "${PUBLIC_HEADERS:?}"
[[ -f "$LIB_A" ]] || { echo "install: $LIB_A not found: \`make lib\` builds it" >&2; exit 2; }
mkdir -p -- "$root" ||
  { echo "install: cannot create $root" >&2; exit 1; }
stage="$(mktemp -d -- "$root/.zephyr-install.XXXXXX")" ||
  { echo "install: cannot write under $root" >&2; exit 1; }
trap 'rm -rf -- "$stage"' EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP
files=()
put() {  # put SOURCE DEST-relative-to-prefix
  install -D -m 644 -- "$1" "$stage/$2"
  files+=("$2")
}
for h in $PUBLIC_HEADERS; do put "$h" "include/zephyr/$h"; done
put "$LIB_A" "lib/lib$LIB_NAME.a"
for p in ${PROFILE_FILES:-}; do put "$p" "share/zephyr/profiles/$(basename -- "$p")"; done
for pair in ${EXTRA_INSTALL:-}; do put "${pair%%=*}" "${pair#*=}"; done
# PIMeval's host API on the engine (docs/pim.md): its header, the archive of the API and the
# engine's objects, and lib/libpimeval.a, a GNU ld script naming that archive by its final path
# and the shared libraries the engine needs (Debian ships Highway as a shared library only), so
# that PIMbench's link line `g++ prog.cpp -std=c++17 -I… -L… -lpimeval` links as it stands.
if [[ -n "${PIMEVAL_A:-}" ]]; then
  [[ -f "$PIMEVAL_A" ]] || { echo "install: $PIMEVAL_A not found (make pimeval-lib)" >&2; exit 2; }
  put tools/pimeval/libpimeval.h include/libpimeval.h
  put "$PIMEVAL_A" lib/libzephyr-pimeval.a
  ld_prefix="${prefix//\\/\\\\}"
  ld_prefix="${ld_prefix//\"/\\\"}"
  printf '/* GNU ld script: PIMeval%s host API on the emulated Zephyr (docs/pim.md). */\nINPUT("%s/lib/libzephyr-pimeval.a" %s -lgomp -lpthread)\n' \
    "'s" "$ld_prefix" "$(pkg-config --libs libhwy fmt)" > "$stage/lib/libpimeval.a"
  files+=("lib/libpimeval.a")
fi
# pkg-config's own escaping: a space in a variable's value is written '\ '.
pc_prefix="${prefix// /\\ }"
mkdir -p -- "$stage/lib/pkgconfig"
printf '%s\n' "prefix=$pc_prefix" 'includedir=${prefix}/include/zephyr' \
  'libdir=${prefix}/lib' 'profilesdir=${prefix}/share/zephyr/profiles' '' \
  "Name: $LIB_NAME" \
  'Description: The emulated WaveTracer Zephyr bit-serial SIMD array and its MultiC-like API' \
  "Version: ${LIB_VERSION:-0}" "Requires: ${PC_REQUIRES:-}" \
  "Libs: -L\${libdir} -l$LIB_NAME -lgomp -lpthread" 'Cflags: -I${includedir}' \
  > "$stage/lib/pkgconfig/$LIB_NAME.pc"
files+=("lib/pkgconfig/$LIB_NAME.pc")
printf '%s\n' "${files[@]}" > "$stage/list"
# Every file staged: move them in (each move is a rename on the same file system), then the
# list, last.
for f in "${files[@]}"; do
  mkdir -p -- "$(dirname -- "$root/$f")"
  mv -f -- "$stage/$f" "$root/$f"
done
mkdir -p -- "$(dirname -- "$list")"
install -m 644 -- "$stage/list" "$list"
echo "installed $(wc -l < "$list") files under $root (list: $list)"
