#!/bin/sh
# SPDX-License-Identifier: MIT
# exports.sh LIB: the shared library's dynamic symbol table holds the public API
# (btdf_*) and nothing else. A cloned (target_clones) internal function is the usual
# way to break this: GCC exports its resolver whatever -fvisibility says.
set -u
lib=$1
nm=${NM:-nm}
command -v "$nm" >/dev/null 2>&1 || { echo "no nm to read $lib"; exit 77; }
syms=$("$nm" -D --defined-only "$lib") || { echo "cannot read $lib"; exit 1; }
[ -n "$syms" ] || { echo "no dynamic symbols in $lib"; exit 1; }
api=$(printf '%s\n' "$syms" | awk '{print $3}' | grep -c '^btdf_')
others=$(printf '%s\n' "$syms" | awk '{print $3}' | grep -v '^btdf_' | grep -v '^_' || true)
echo "$api btdf_ symbols exported"
if [ -n "$others" ]; then
    echo "exported symbols outside the API:"; printf '%s\n' "$others"; exit 1
fi
[ "$api" -gt 50 ] || { echo "only $api btdf_ symbols: the API is missing"; exit 1; }
