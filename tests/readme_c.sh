#!/bin/sh
# SPDX-License-Identifier: MIT
# readme_c.sh EXE: runs the README's C example (built from README.md by readme_c.py)
# in an empty folder: it prints rho and rho_r and writes ice.csv; with the build made to
# fail it prints the library's message, writes nothing and exits cleanly (its table
# pointer starts NULL; the program is compiled so that an uninitialised one is not).
set -u
EXE=$1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
pass=0; failn=0
ok() { pass=$((pass + 1)); echo "ok $pass - $1"; }
no() { failn=$((failn + 1)); echo "not ok - $1"; }
cd "$W" || exit 1
if "$EXE" >out 2>err && grep -q '^rho = [0-9.e+-]* 1/sr, rho_r = [0-9.e+-]* 1/sr$' out &&
   [ -s ice.csv ] && [ ! -s err ]; then ok "the example builds ice.csv and prints rho, rho_r"
else no "the example (exit $?): $(cat out err)"; fi
rm -f ice.csv
"$EXE" fail >out 2>err; st=$?
if [ "$st" -eq 0 ] && grep -q '^btdf: .*smoothness' err && [ ! -e ice.csv ]; then
    ok "a failed build: the message, no file, no crash"
else no "a failed build (exit $st): $(cat err)"; fi
echo "$pass passed, $failn failed"
[ "$failn" -eq 0 ]
