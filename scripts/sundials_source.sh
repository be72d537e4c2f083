#!/usr/bin/env bash
# Fetches Debian's SUNDIALS source package (the version libsundials-dev has, 6.4.1 on bookworm)
# into build/cross/src/ with `apt-get source`, after adding a deb-src entry made from this
# machine's own apt sources (their URIs, suites and components, copied; no host name is written
# into the repository). Idempotent: does nothing when the source tree is already there.
#   bash scripts/sundials_source.sh            # prints the source directory
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="$root/build/cross/src"
existing=$(ls -d "$dest"/sundials-*/ 2>/dev/null | head -n1 || true)
if [[ -n $existing && -f $existing/src/cvode/cvode.c ]]; then
    echo "${existing%/}"
    exit 0
fi
sudo_cmd=()
[[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
list=/etc/apt/sources.list.d/impact-deb-src.sources
if ! apt-get source --print-uris sundials >/dev/null 2>&1; then
    # deb822 stanzas of type deb, and one-line "deb" entries, re-typed as deb-src.
    tmp=$(mktemp)
    for f in /etc/apt/sources.list.d/*.sources; do
        [[ -f $f && $f != "$list" ]] || continue
        awk 'BEGIN{RS=""; ORS="\n\n"} /(^|\n)Types:[^\n]*deb( |\n|$)/ {
                 sub(/Types:[^\n]*/, "Types: deb-src"); print }' "$f" >> "$tmp"
    done
    if [[ -f /etc/apt/sources.list ]]; then
        grep -E '^deb ' /etc/apt/sources.list | sed -E 's/^deb /deb-src /' \
            > "${tmp}.list" || true
        [[ -s ${tmp}.list ]] && "${sudo_cmd[@]}" cp "${tmp}.list" /etc/apt/sources.list.d/impact-deb-src.list
        rm -f "${tmp}.list"
    fi
    [[ -s $tmp ]] && "${sudo_cmd[@]}" cp "$tmp" "$list"
    rm -f "$tmp"
    "${sudo_cmd[@]}" apt-get update -qq >&2
fi
mkdir -p "$dest"
(cd "$dest" && apt-get source -qq sundials >&2)
existing=$(ls -d "$dest"/sundials-*/ | head -n1)
echo "${existing%/}"
