#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Reads the tool's .exr tables with the OpenEXR Python bindings (their own copy of the
OpenEXR library, not the one btdftab links) and checks every pixel against the CSV the
tool writes for the same options, rounded to binary32. A writer bug and a matching bug
in our reader cannot hide each other here.

Usage: exr_foreign.py BTDFTAB [WORKDIR]   (needs: pip install OpenEXR numpy)
Ends with "N passed, N failed"."""
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenEXR

CASES = [
    # the tolerance sweep of glass (n 1.5, s 3), the default range 0:90 down to 1e-3;
    # 3e-4 and 1e-4 over narrower ranges (over 0:90 their CSVs are 0.6 to 1.2 GB)
    *[["--ior", "1.5", "-s", "3", "--tolerance", t] for t in
      ("1e-1", "3e-2", "2e-2", "1e-2", "3e-3", "1e-3")],
    ["--ior", "1.5", "-s", "3", "--tolerance", "3e-4", "--theta-i", "0:45"],
    ["--ior", "1.5", "-s", "3", "--tolerance", "1e-4", "--theta-i", "20:30"],
    ["--ior", "1.5", "-s", "12", "--tolerance", "1e-1"],
    ["--ior", "1.5", "-s", "12", "--tolerance", "3e-4", "--theta-i", "60:90"],
    ["--ior", "1.31", "-s", "20"],  # the README's ice
    ["--ior", "1.5,1.51,1.52", "-s", "3", "--tolerance", "1e-2"],  # three channels
    ["--ior", "0.6666667", "-s", "6", "--theta-i", "0:60"],  # reciprocal kind
    ["--ior", "1.5", "-s", "3", "--grid", "7,46,37"],  # grid: 46 rows, 37 columns
    ["--ior", "1.5", "-s", "3", "--grid", "3,17,5", "--theta-o", "95:170"],
    # the reflection (its own kind), and both parts in one file (the reflection's parts
    # after the transmission's, btdf.part = "reflection" on each)
    ["--ior", "1.5", "-s", "3", "--part", "reflection", "--tolerance", "1e-2"],
    ["--ior", "1.5", "-s", "3", "--part", "both", "--tolerance", "1e-2"],
    ["--ior", "0.6666667", "-s", "6", "--part", "both", "--theta-i", "30:50",
     "--tolerance", "1e-2"],
    ["--ior", "1.5,1.51,1.52", "-s", "6", "--part", "both", "--tolerance", "1e-2",
     "--theta-i", "0:40"],
    # the other models' reflection nodes hold the Beckmann factor and are continued
    # past the horizon (docs/tables.md): the file must still hold rho_r itself
    ["--model", "smith", "--ior", "1.5", "-s", "3", "--part", "reflection",
     "--tolerance", "1e-2"],
    ["--model", "full", "--ior", "0.6666667", "-s", "3", "--part", "both",
     "--tolerance", "2e-2", "--theta-i", "40:80"],
]


def read_csv(path):
    """Slices in file order: (part, ti, rows, cols, values[nrows, ncols, channels]); part
    is the row's last column in a file holding both parts, else the file's own."""
    slices = {}
    order = []
    nch = None
    part_col = False
    own = "transmission"
    with open(path) as f:
        for line in f:
            if line.startswith("# kind: facet-reflection"):
                own = "reflection"
            if line.startswith("#"):
                continue
            if line.startswith("theta_i_deg"):
                nch = 3 if "rho_r" in line else 1
                part_col = line.rstrip("\n").endswith(",part")
                continue
            c = line.rstrip("\n").split(",")
            part = c.pop() if part_col else own
            ti, row, col = float(c[-3]), float(c[-2]), float(c[-1])
            vals = [float(v) for v in c[3:3 + nch]]
            if (part, ti) not in slices:
                slices[(part, ti)] = {}
                order.append((part, ti))
            slices[(part, ti)][(row, col)] = vals
    out = []
    for key in order:
        nodes = slices[key]
        rows = sorted({r for r, _ in nodes})
        cols = sorted({c for _, c in nodes})
        v = np.array([[nodes[(r, c)] for c in cols] for r in rows], dtype=np.float64)
        out.append((key[0], key[1], rows, cols, v))
    return out, nch


def check(tool, args, work):
    csv = os.path.join(work, "t.csv")
    exr = os.path.join(work, "t.exr")
    for out in (csv, exr):
        r = subprocess.run([tool, "tabulate", *args, "--best-effort", "-q", "-o", out],
                           capture_output=True, text=True)
        if r.returncode not in (0, 3):
            return "tabulate %s failed: %s" % (out, r.stderr.strip())
    slices, nch = read_csv(csv)
    f = OpenEXR.File(exr, separate_channels=True)
    if len(f.parts) != len(slices):
        return "%d parts, %d slices in the CSV" % (len(f.parts), len(slices))
    names = ["Y"] if nch == 1 else ["R", "G", "B"]
    for k, (part, (which, ti, rows, cols, v)) in enumerate(zip(f.parts, slices)):
        h = part.header
        if h.get("btdf.part", "transmission") != which:
            return "part %d: btdf.part %r, the CSV's slice is of the %s" % (
                k, h.get("btdf.part"), which)
        if float(np.asarray(h["btdf.ti"]).ravel()[0]) != ti:
            return "part %d: btdf.ti differs from the CSV" % k
        if [float(x) for x in h["btdf.rows"].split()] != rows or \
                [float(x) for x in h["btdf.cols"].split()] != cols:
            return "part %d: node coordinates differ from the CSV" % k
        if set(part.channels) != set(names):
            return "part %d: channels %s" % (k, sorted(part.channels))
        for ch, name in enumerate(names):
            px = part.channels[name].pixels
            if px.dtype != np.float32 or px.shape != (len(rows), len(cols)):
                return "part %d %s: %s %s" % (k, name, px.dtype, px.shape)
            want = v[:, :, ch].astype(np.float32)
            bad = np.argwhere(px != want)
            if bad.size:
                r, c = bad[0]
                return ("part %d (%d x %d) channel %s node (%d, %d): file %.9g, table %.9g; "
                        "%d nodes differ" % (k, len(rows), len(cols), name, r, c, px[r, c],
                                             want[r, c], len(bad)))
    return None


# A pane's grid (docs/pane.md, "Tables"): every layer of the .exr against the rows of
# the .csv of the same options, rounded to binary32. (front s, back, grid, more options)
PANE_CASES = [
    ["--ior", "1.5", "-s", "3", "--back", "smooth", "--thickness", "4"],  # default grid
    ["--ior", "1.5", "-s", "2", "--back", "6", "--absorption", "0.03", "--grid", "31,23,19"],
    ["--ior", "1.5,1.51,1.52", "-s", "4", "--back", "smooth", "--grid", "12,15,9"],
]
# layer name (the front's transmission has none) -> the CSV's (light, part)
PANE_LAYERS = {"": ("front", "transmission"), "front_reflection.": ("front", "reflection"),
               "back_transmission.": ("back", "transmission"),
               "back_reflection.": ("back", "reflection")}


def check_pane(tool, args, work):
    """Part k is theta_i node k; its row i is theta_o = 90 + t_i (a reflection's tr =
    90 - t_i), which is the CSV's node nto - 1 - i of t (from the face); column j is
    phi node j. back_delta, for a flat back, holds the back's mirror weight of the slice
    at every node."""
    csv = os.path.join(work, "p.csv")
    exr = os.path.join(work, "p.exr")
    for out in (csv, exr):
        r = subprocess.run([tool, "tabulate", *args, "-q", "-o", out], capture_output=True,
                           text=True)
        if r.returncode != 0:
            return "tabulate %s failed: %s" % (out, r.stderr.strip())
    with open(csv) as fh:
        head = fh.readline().rstrip("\n").split(",")
        rows = [l.rstrip("\n").split(",") for l in fh if not l.startswith("#")]
    fcols = [i for i, h in enumerate(head) if h.startswith("f")]
    nch = len(fcols)
    blocks, delta = {}, {}
    for r in rows:  # in file order: block by block, theta_i, t, phi
        if r[1].endswith("-delta"):
            delta.setdefault((r[0], r[1]), []).append([float(r[i]) for i in fcols])
        else:
            blocks.setdefault((r[0], r[1]), []).append([float(x) for x in r[2:5]] +
                                                       [float(r[i]) for i in fcols])
    f = OpenEXR.File(exr, separate_channels=True)
    nti = len(f.parts)
    first = f.parts[0]
    nto, nphi = first.channels["Y" if nch == 1 else "R"].pixels.shape
    names = ["Y"] if nch == 1 else ["R", "G", "B"]
    checked = 0
    for pre, key in PANE_LAYERS.items():
        v = np.array(blocks[key]).reshape(nti, nto, nphi, 3 + nch)
        for k, part in enumerate(f.parts):
            ti = float(np.asarray(part.header["btdf.ti"]).ravel()[0])
            if abs(ti * 180.0 / np.pi - v[k, 0, 0, 0]) > 1e-9:
                return "part %d: btdf.ti %.17g, the CSV's theta_i %s" % (k, ti, v[k, 0, 0, 0])
            for ch, name in enumerate(names):
                px = part.channels[pre + name].pixels
                want = v[k, ::-1, :, 3 + ch].astype(np.float32)
                bad = np.argwhere(px != want)
                if px.shape != (nto, nphi) or bad.size:
                    i, j = bad[0] if bad.size else (0, 0)
                    return ("part %d layer %r %s node (%d, %d): file %.9g, csv %.9g; %d differ"
                            % (k, pre, name, i, j, px[i, j], want[i, j], len(bad)))
                checked += px.size
    for k, part in enumerate(f.parts):
        has = any(c.startswith("back_delta.") for c in part.channels)
        if has != (("back", "reflection-delta") in delta):
            return "part %d: back_delta layer %s, the CSV's delta rows %s" % (
                k, has, ("back", "reflection-delta") in delta)
        for ch, name in enumerate(names if has else []):
            px = part.channels["back_delta." + name].pixels
            if np.any(px != np.float32(delta[("back", "reflection-delta")][k][ch])):
                return "part %d: back_delta %s is not the CSV's weight" % (k, name)
    if checked != nch * sum(len(b) for b in blocks.values()):
        return "%d values checked, the CSV has %d" % (checked,
                                                      nch * sum(len(b) for b in blocks.values()))
    return None


def main():
    tool = sys.argv[1]
    work = sys.argv[2] if len(sys.argv) > 2 else tempfile.mkdtemp(prefix="btdf-foreign-")
    passed = failed = 0
    for args in CASES:
        why = check(tool, args, work)
        label = " ".join(args)
        if why is None:
            passed += 1
            print("ok   %s" % label)
        else:
            failed += 1
            print("FAIL %s: %s" % (label, why))
    for args in PANE_CASES:
        why = check_pane(tool, args, work)
        label = "pane " + " ".join(args)
        if why is None:
            passed += 1
            print("ok   %s" % label)
        else:
            failed += 1
            print("FAIL %s: %s" % (label, why))
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
