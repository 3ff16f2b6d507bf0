#!/bin/sh
# SPDX-License-Identifier: MIT
# install.sh: meson install into a staging prefix, then build examples/api.c against
# it with pkg-config as a user of the library would, and run it. Also checks that the
# shared library exports the API's btdf_ symbols and nothing else.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
pass=0; failn=0
ok() { pass=$((pass + 1)); echo "ok $pass - $1"; }
no() { failn=$((failn + 1)); echo "not ok - $1"; }
if meson setup "$W/build" "$ROOT" --prefix="$W/stage" --libdir=lib -Dtests=false >"$W/log" 2>&1 &&
   meson install -C "$W/build" >>"$W/log" 2>&1; then ok "meson install into a staging prefix"
else no "meson install"; cat "$W/log"; fi
missing=""
for f in include/btdf/btdf.h include/btdf/btdf_config.h include/btdf/btdf_preview.h \
         include/btdf/btdf_scatfun.h include/btdf/btdf_io.h share/man/man1/btdftab.1 \
         share/bash-completion/completions/btdftab \
         lib/libbtdf.so lib/libbtdf.a lib/pkgconfig/btdf.pc bin/btdftab; do
    [ -e "$W/stage/$f" ] || missing="$missing $f"
done
[ -z "$missing" ] && ok "headers, libraries, btdf.pc and btdftab installed" || no "missing:$missing"
# The Python package beside the library, pointing at the installed library, and the
# Mitsuba plugin beside it (it reaches the library through the package).
PYD=$W/stage/lib/btdftab/python
if [ -e "$PYD/btdftab_mitsuba/plugin.py" ] && [ -e "$PYD/btdftab/__init__.py" ] &&
   [ ! -e "$PYD/btdftab_mitsuba/libbtdf.py" ] &&
   lib=$(python3 -c "exec(open('$PYD/btdftab/_installed.py').read()); print(LIBRARY)") &&
   [ "$lib" = "$W/stage/lib/libbtdf.so.0" ] && [ -e "$lib" ]; then
    ok "btdftab and the Mitsuba plugin installed in lib/btdftab/python, loading $lib"
else no "btdftab and the Mitsuba plugin in lib/btdftab/python (library: ${lib:-none})"; fi
others=$(nm -D --defined-only "$W/stage/lib/libbtdf.so" | awk '{print $3}' | grep -v '^btdf_' | grep -v '^_' || true)
[ -z "$others" ] && ok "only btdf_ symbols are exported" || { no "exported non-API symbols"; echo "$others"; }
export PKG_CONFIG_PATH="$W/stage/lib/pkgconfig"
if cc -std=c99 -Wall -Wextra -Werror "$ROOT/examples/api.c" -o "$W/api" \
      $(pkg-config --cflags --libs btdf) 2>"$W/cc.log"; then ok "examples/api.c builds with pkg-config"
else no "examples/api.c"; cat "$W/cc.log"; fi
(cd "$W" && LD_LIBRARY_PATH="$W/stage/lib" ./api) && [ -s "$W/api-example.csv" ] && \
    ok "examples/api.c runs against the installed library" || no "examples/api.c run"
echo "$pass passed, $failn failed"
[ "$failn" -eq 0 ]
