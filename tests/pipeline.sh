#!/bin/sh
# SPDX-License-Identifier: MIT
# pipeline.sh BTDFTAB: the examples/library Makefile as a user runs it. make -j2 builds
# everything; a second make does nothing; the outputs equal a serial build's bytes; a
# build killed midway leaves no partial file and the next make finishes the job.
set -u
B=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SRC=$(cd "$(dirname "$0")/../examples/library" && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
pass=0; failn=0
ok() { pass=$((pass + 1)); echo "ok $pass - $1"; }
no() { failn=$((failn + 1)); echo "not ok - $1"; }
for d in par ser kill; do cp -r "$SRC" "$W/$d"; done

(cd "$W/par" && make -j2 BTDFTAB="$B" >log 2>&1) && ok "make -j2 builds everything" || { no "make -j2"; cat "$W/par/log"; }
(cd "$W/par" && make -q BTDFTAB="$B") && ok "a second make has nothing to do" || no "second make would rebuild"
(cd "$W/ser" && make -j1 BTDFTAB="$B" >log 2>&1) && ok "serial make" || no "serial make"
if diff -r "$W/par/out" "$W/ser/out" >/dev/null; then ok "parallel and serial outputs are byte-identical"
else no "parallel and serial outputs differ"; diff -rq "$W/par/out" "$W/ser/out"; fi

# Kill a parallel build midway: every file present must be complete (equal to the
# serial build's), no temporary file may remain, and make must then finish the job.
cd "$W/kill"
setsid make -j2 BTDFTAB="$B" >log 2>&1 &
pid=$!
sleep 4
kill -TERM -- -"$pid" 2>/dev/null
wait "$pid" 2>/dev/null
left=$(find out -name '*.tmp*' 2>/dev/null | wc -l)
[ "$left" -eq 0 ] && ok "no temporary file left after the kill" || { no "temporary files left"; find out -name '*.tmp*'; }
bad=0
for f in out/*; do
    [ -e "$f" ] || continue
    case "$f" in out/scene.done) continue ;; esac
    cmp -s "$f" "$W/ser/$f" || { bad=1; echo "partial or different: $f"; }
done
[ "$bad" -eq 0 ] && ok "every file present after the kill is complete" || no "partial file after kill"
make -j2 BTDFTAB="$B" >log2 2>&1 && diff -r out "$W/ser/out" >/dev/null && \
    ok "the next make finishes the job, same bytes" || no "make after kill"
# The program is a prerequisite of every rule: a newer btdftab (an upgrade) makes
# every output out of date.
cd "$W/par" && cp "$B" "$W/btdftab-new" && sleep 1 && touch "$W/btdftab-new"
if make -q BTDFTAB="$W/btdftab-new"; then no "a newer btdftab leaves the outputs up to date"
else ok "a newer btdftab makes the outputs out of date"; fi
echo "$pass passed, $failn failed"
[ "$failn" -eq 0 ]
