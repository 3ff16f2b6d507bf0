#!/bin/sh
# SPDX-License-Identifier: MIT
# radiance.sh BTDFTAB PYTHON: writes Radiance BSDF files (tensor tree and Klems) and checks
# them with Radiance itself (PYTHON must import pyradiance, which bundles Radiance's
# programs and BSDF library): the file loads with its four blocks (both transmissions
# and both reflections, in the tree and the Klems file alike), Radiance's lookup equals
# the report's probes for every block, and rtrace gives the hemispherical transmittance
# (reflectance) within the report's e_T (tests/radiance_check.py). A colour file (three
# --ior values, Klems quarter basis: CIE X, Y, Z matrices) the same way, each of rtrace's
# R, G, B against its channel; a colour tree (three --ior values, tolerance 0.5: Y, u', v'
# trees) likewise. Also: bad --basis values and two channels fail cleanly.
# Ends with "N passed, N failed".
set -u
B="$1"
PY="$2"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
pass=0
failn=0
tally() { # the "N passed, N failed" line of one radiance_check.py run
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$1" | tail -n 1)
    p=$(echo "$line" | sed -n 's/^\([0-9]*\) passed.*/\1/p'); p=${p:-0}
    f=$(echo "$line" | sed -n 's/.*passed, \([0-9]*\) failed/\1/p'); f=${f:-1}
    pass=$((pass + p)); failn=$((failn + f))
}
ok() { pass=$((pass + 1)); echo "ok - $1"; }
no() { failn=$((failn + 1)); echo "not ok - $1"; }

if ! "$PY" -c 'import pyradiance' 2>/dev/null; then
    echo "not ok - $PY cannot import pyradiance (pip install pyradiance in a venv)"
    echo "0 passed, 1 failed"
    exit 1
fi
here=$(dirname "$0")
# colour: indices far apart, so that the channels' colours are saturated enough to tell
# Radiance's RGB primaries from others (with NTSC's the check's colour loss fails)
for run in "tree3 1.5 0.2" "klems-full 1.5 -" "klems-quarter 1.2,1.5,2.2 -" \
    "tree3 1.2,1.5,2.2 0.5"; do
    set -- $run
    basis=$1
    ior=$2
    tol=""
    [ "$3" != - ] && tol="--tolerance $3"
    if "$B" tabulate -q --ior "$ior" -s 3 --basis "$basis" $tol -o "$W/glazing.xml" \
        --report "$W/glazing.json"; then
        ok "tabulate --ior $ior --basis $basis $tol -o glazing.xml"
        "$PY" "$here/radiance_check.py" "$W/glazing.xml" "$W/glazing.json" | tee "$W/check.log"
        tally "$W/check.log"
    else
        no "tabulate --ior $ior --basis $basis $tol -o glazing.xml"
    fi
    rm -f "$W"/glazing.*
done

# A pane's system (docs/pane.md): checkBSDF's largest hemispherical transmission from
# either side against btdftab albedo --back at normal incidence, within 1 % (Klems
# quarter: its first patch spans 0-9 deg, over which T changes by 0.1 %), and the
# reciprocity of the Klems transmission below 5 % on average (measured 0.3 %).
PYR=$("$PY" -c 'import os, pyradiance; print(os.path.dirname(pyradiance.__file__))')
"$B" tabulate --back smooth --thickness 4 -s 3 --basis klems-quarter -q -o "$W/pane.xml" &&
    RAYPATH=".:$PYR/lib" "$PYR/bin/checkBSDF" "$W/pane.xml" >"$W/ck" 2>&1 &&
    "$B" albedo --back smooth --thickness 4 -s 3 0 >"$W/alb" &&
    awk -F'\t' -v alb="$(tail -n 1 "$W/alb")" '
        BEGIN { split(alb, a, ","); tf = a[2] * 100; tb = a[5] * 100 }
        /^Ext->Int Trans/ { ef = $4 + 0 } /^Int->Ext Trans/ { eb = $4 + 0 }
        /^Transmission/ { rec = $3 + 0 }
        END { bad = (ef - tf) ^ 2 > (tf / 100) ^ 2 || (eb - tb) ^ 2 > (tb / 100) ^ 2 || rec > 5
              printf "# checkBSDF T %g %g, ours %g %g, reciprocity avg %g %%\n", ef, eb, tf, tb, rec
              exit bad }' "$W/ck" &&
    ok "pane: checkBSDF's T within 1 % of ours, reciprocity below 5 %" ||
    no "pane: checkBSDF against btdftab albedo --back"

# A colour pane (three indices, Klems): Radiance reads it as a colour BSDF (checkBSDF's
# "Color: 1"), and its largest hemispherical transmission from outside (CIE Y, %) is
# within 1 % of the Y of our three channels' T at normal incidence (Klems full: its first
# patch spans 0-5 deg). Y = 0.2651 R + 0.6701 G + 0.0648 B: the Y row of RGB -> XYZ for
# Radiance's default primaries (0.640, 0.330), (0.290, 0.600), (0.150, 0.060) and
# equal-energy white, by which the file's X, Y, Z were made (src/radiance/radiance.c).
"$B" tabulate --back smooth --thickness 4 -s 3 --ior 1.49,1.5,1.52 --basis klems-full -q \
    -o "$W/pcol.xml" &&
    RAYPATH=".:$PYR/lib" "$PYR/bin/checkBSDF" "$W/pcol.xml" >"$W/ck3" 2>&1 &&
    grep -q '^Color: 1' "$W/ck3" &&
    "$B" albedo --back smooth --thickness 4 -s 3 --ior 1.49,1.5,1.52 0 >"$W/alb3" &&
    awk -F'\t' -v alb="$(tail -n 1 "$W/alb3")" '
        BEGIN { split(alb, a, ","); ty = 100 * (0.2651 * a[2] + 0.6701 * a[8] + 0.0648 * a[14]) }
        /^Ext->Int Trans/ { ef = $4 + 0 }
        END { printf "# colour pane: checkBSDF Y %g %%, ours %g %%\n", ef, ty
              exit (ef - ty) ^ 2 > (ty / 100) ^ 2 }' "$W/ck3" &&
    ok "colour pane: Radiance reads a colour BSDF, its Y within 1 % of ours" ||
    no "colour pane: $(cat "$W/ck3" 2>/dev/null | head -n 12)"
"$B" tabulate --back smooth -s 3 --ior 1.49,1.5,1.52 --basis tree3 -o "$W/pct.xml" 2>"$W/err"
[ $? -eq 2 ] && grep -q "takes the Klems bases" "$W/err" && [ ! -e "$W/pct.xml" ] &&
    ok "a colour pane tree3: usage error naming the bases that take it" || no "colour pane tree3: $(cat "$W/err")"

# bad input: usage status 2, the value named, nothing written
"$B" tabulate --basis klems-eighth -o "$W/t.xml" 2>"$W/err"
[ $? -eq 2 ] && grep -q "klems-eighth" "$W/err" && [ ! -e "$W/t.xml" ] &&
    ok "--basis klems-eighth: usage error naming the value" || no "--basis klems-eighth"
"$B" tabulate --ior 1.5,1.6 --basis klems-quarter -o "$W/t.xml" 2>"$W/err"
[ $? -eq 2 ] && grep -q "1 value or 3" "$W/err" && [ ! -e "$W/t.xml" ] &&
    ok "two channels: usage error" || no "two channels to .xml"
"$B" tabulate --basis klems-half -o "$W/t.csv" 2>"$W/err"
[ $? -eq 2 ] && grep -q "\.xml output only" "$W/err" && [ ! -e "$W/t.csv" ] &&
    ok "--basis with a .csv: usage error" || no "--basis with a .csv"
echo "$pass passed, $failn failed"
[ "$failn" -eq 0 ]
