#!/bin/sh
# SPDX-License-Identifier: MIT
# mitsuba.sh: the Mitsuba 3 plugin (python/btdftab_mitsuba) checked in a venv with
# mitsuba from PyPI: eval against btdf_table_eval (transmission) and btdf_eval_r
# (reflection), chi-square tests of the sampling (each lobe and both together), the mean
# sampled weight against T(ti) and R(ti) + T(ti) on both sides, a white-furnace render,
# and a render of a rough face against the analytic mode; then the thin sheet
# btdftab_pane (tests/mitsuba_pane_checks.py: eval against btdf_pane_eval, chi-square,
# mean weights against the BSDF's integral, a white furnace). Runs scalar_rgb always,
# llvm_ad_rgb when an LLVM 16 or newer is installed (Debian 12: apt-get install
# libllvm19; Dr.Jit's LLVM backend cannot compile its min/max with the LLVM 15 of
# Debian 12's default llvm package).
# Usage: sh tests/mitsuba.sh [BUILD_DIR]   (default build). Ends with "N passed, N failed".
# MITSUBA_VENV names the venv to create or reuse (default: a temporary folder).
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$ROOT/build}
BUILD=$(cd "$BUILD" 2>/dev/null && pwd) ||
    { echo "no build folder ${1:-build}"; echo "0 passed, 1 failed"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
VENV=${MITSUBA_VENV:-$W/venv}
pass=0; failn=0
ok() { pass=$((pass + 1)); echo "ok - $1"; }
no() { failn=$((failn + 1)); echo "not ok - $1"; }
finish() { echo "$pass passed, $failn failed"; [ "$failn" -eq 0 ]; exit $?; }

# The versions these checks were written against; a newer release may change the API.
PIP_PKGS="mitsuba==3.9.1 drjit==1.5.0 numpy"
if [ -x "$VENV/bin/python" ] || python3 -m venv "$VENV" >"$W/venv.log" 2>&1; then
    ok "venv $VENV"
else no "python3 -m venv (Debian: apt-get install python3-venv)"; cat "$W/venv.log"; finish; fi
if "$VENV/bin/pip" install -q $PIP_PKGS >"$W/pip.log" 2>&1; then ok "pip install $PIP_PKGS"
else no "pip install $PIP_PKGS"; tail -n 20 "$W/pip.log"; finish; fi

BT=$BUILD/tools/btdftab
[ -x "$BT" ] && [ -e "$BUILD/libbtdf.so" ] ||
    { no "no $BT or $BUILD/libbtdf.so: build first"; finish; }
export BTDFTAB_LIBRARY="$BUILD/libbtdf.so"

# The tables every kind btdftab writes: facet, grid, facet-reciprocal, 3 channels, a back
# side; .csv and .exr readers both.
T=$W/tables
mkdir -p "$T"
tabs_ok=1
while read -r name args; do
    # shellcheck disable=SC2086
    "$BT" tabulate $args -o "$T/$name" --report "$T/${name%.*}.json" --quiet ||
        { tabs_ok=0; echo "tabulate $name failed"; }
done <<TABLES
f15.exr --ior 1.5 -s 3
f15s100.exr --ior 1.5 -s 100
r066s6.exr --ior 0.6666667 -s 6
g15.exr --ior 1.5 -s 3 --grid 30,46,37
f3.exr --ior 1.51,1.52,1.53 -s 3
f15back.exr --ior 1.5 -s 3 --side leave
face.csv --ior 0.7142857 -s 3
fsm15.exr --model smith --ior 1.5 -s 3
rsm066s6.exr --model smith --ior 0.6666667 -s 6
ffu1.exr --model full --ior 1.5 -s 1 --tolerance 1e-2
TABLES
[ "$tabs_ok" -eq 1 ] && ok "tables written by btdftab" || no "tables"

run() { # variant: the checks' own "N passed, N failed" lines are added to the tally
    # (the interface's, then the thin sheet's: tests/mitsuba_pane_checks.py)
    for script in mitsuba_checks.py mitsuba_pane_checks.py; do
        log=$W/$1-$script.log
        "$VENV/bin/python" "$ROOT/tests/$script" "$1" "$T" >"$log" 2>&1
        cat "$log"
        line=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$log" | tail -n 1)
        if [ -z "$line" ]; then no "$1 $script did not finish"; continue; fi
        pass=$((pass + ${line%% passed*})); b=${line#*passed, }; failn=$((failn + ${b%% failed}))
    done
}

run scalar_rgb

# An LLVM the Dr.Jit backend can use (16 or newer), unless the caller chose one.
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
    for v in 19 18 17 16; do
        for d in /usr/lib/x86_64-linux-gnu /usr/lib/aarch64-linux-gnu /usr/lib64 /usr/lib; do
            if [ -e "$d/libLLVM-$v.so" ]; then DRJIT_LIBLLVM_PATH=$d/libLLVM-$v.so; break 2; fi
        done
    done
fi
if [ -n "${DRJIT_LIBLLVM_PATH:-}" ]; then
    export DRJIT_LIBLLVM_PATH
    echo "# llvm_ad_rgb with $DRJIT_LIBLLVM_PATH"
    run llvm_ad_rgb
else
    echo "# llvm_ad_rgb skipped: no libLLVM 16 or newer (Debian 12: apt-get install libllvm19)"
fi
finish
