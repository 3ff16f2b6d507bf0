#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# csv_readers.py BTDFTAB: a table CSV is read by the one call docs/formats.md
# documents, with numpy and with pandas (whichever is installed): the column names of
# the header row, every node row, and the values bit for bit as the file prints them
# (pandas 2 needs float_precision="round_trip" for that: its default parser may be one
# unit in the last place off; pandas 3 parses exactly by default and deprecates the
# argument, so the documented call passes it only to pandas < 3).
import os
import subprocess
import sys
import tempfile
import warnings

tool = sys.argv[1]
passed = failed = 0


def check(cond, what):
    global passed, failed
    if cond:
        passed += 1
        print("ok %d - %s" % (passed, what))
    else:
        failed += 1
        print("not ok - %s" % what)


def node_rows(path):
    """The node rows as the file holds them: neither the header nor a comment."""
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")]
    return [l.rstrip("\n").split(",") for l in lines[1:]]


with tempfile.TemporaryDirectory() as w:
    cases = [("adaptive", ["--ior", "1.5", "-s", "3", "--tolerance", "5e-3"], "rho"),
             ("rgb grid", ["--ior", "1.5,1.52,1.54", "--grid", "4,6,5"], "rho_g"),
             ("leaving", ["--ior", "0.7", "-s", "6", "--tolerance", "1e-2", "--theta-i", "0:40"],
              "rho")]
    for name, args, col in cases:
        path = os.path.join(w, "t.csv")
        subprocess.run([tool, "tabulate", "-q", "--best-effort"] + args + ["-o", path],
                       check=True)
        rows = node_rows(path)
        header = open(path).readline().strip().split(",")
        k = header.index(col)
        want = [float(r[k]) for r in rows]
        try:
            import numpy
            a = numpy.genfromtxt(path, delimiter=",", names=True)
            check(list(a.dtype.names) == header, "%s: numpy.genfromtxt names" % name)
            check(a.shape[0] == len(rows) and list(a[col]) == want,
                  "%s: numpy.genfromtxt reads %d rows, exact values" % (name, len(rows)))
        except ImportError:
            pass
        try:
            import pandas
            kw = ({"float_precision": "round_trip"}
                  if int(pandas.__version__.split(".")[0]) < 3 else {})
            with warnings.catch_warnings():
                # the documented call must not lean on a deprecated argument (pandas 3
                # deprecates float_precision): any warning of the call fails the check
                warnings.simplefilter("error")
                d = pandas.read_csv(path, comment="#", **kw)
            check(list(d.columns) == header, "%s: pandas %s read_csv names"
                  % (name, pandas.__version__))
            check(d.shape[0] == len(rows) and list(d[col]) == want,
                  "%s: pandas.read_csv reads %d rows, exact values" % (name, len(rows)))
        except ImportError:
            pass
    # A pane's grid (docs/pane.md, "Tables"): text columns light and part beside the
    # numbers, read by the calls docs/pane.md gives, the values bit for bit
    path = os.path.join(w, "pane.csv")
    subprocess.run([tool, "tabulate", "-q", "--ior", "1.5", "-s", "2", "--back", "smooth",
                    "--grid", "6,5,4", "-o", path], check=True)
    rows = node_rows(path)
    header = open(path).readline().strip().split(",")
    want = [(r[0], r[1], float(r[5])) for r in rows]
    try:
        import numpy
        a = numpy.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
        got = [(str(x["light"]), str(x["part"]), float(x["f"])) for x in a]
        check(list(a.dtype.names) == header and got == want,
              "pane: numpy.genfromtxt(dtype=None) reads %d rows, sides named, exact values"
              % len(rows))
    except ImportError:
        pass
    try:
        import pandas
        kw = ({"float_precision": "round_trip"}
              if int(pandas.__version__.split(".")[0]) < 3 else {})
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            d = pandas.read_csv(path, comment="#", **kw)
        got = list(zip(d["light"], d["part"], d["f"]))
        ft = d[(d.light == "front") & (d.part == "transmission")]
        check(list(d.columns) == header and got == want and len(ft) == 6 * 5 * 4,
              "pane: pandas.read_csv reads %d rows, sides named, exact values" % len(rows))
    except ImportError:
        pass
print("%d passed, %d failed" % (passed, failed))
sys.exit(1 if failed or passed == 0 else 0)
