#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# plot_bench.py CSV PNG: error against run time from `btdf-bench sweep` (log-log, one
# curve per method and case). Needs matplotlib; only for the picture in docs/.
import csv
import os
import sys

if len(sys.argv) != 3:
    sys.exit("usage: plot_bench.py CSV PNG")
if os.path.realpath(sys.argv[1]) == os.path.realpath(sys.argv[2]):
    sys.stderr.write("plot_bench.py: the picture %s would replace the input CSV: name "
                     "another PNG\n" % sys.argv[2])
    sys.exit(2)

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

rows = list(csv.DictReader(open(sys.argv[1])))
fig, ax = plt.subplots(figsize=(8, 5.5), dpi=110)
colours = {"1.5/3": "tab:blue", "1.5/100": "tab:orange", "1/1.5/6": "tab:green",
           "1.0001/3": "tab:red"}
for method, style in (("adaptive", "o-"), ("uniform", "s--")):
    for case, col in colours.items():
        pts = [(float(r["seconds_tabulation"]), float(r["e_l1"])) for r in rows
               if r["method"] == method and r["case"] == case]
        if pts:
            xs, ys = zip(*sorted(pts))
            ax.plot(xs, ys, style, color=col, label="%s, n/s = %s" % (method, case),
                    mfc="none" if method == "uniform" else col)
ax.axhline(1e-3, color="grey", lw=0.8, ls=":")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("tabulation time, s (median of 3; 2 cores)")
ax.set_ylabel("e_L1 max over ti in [0, 80] deg")
ax.set_title("btdftab: table error against run time")
ax.legend(fontsize=7, ncol=2)
ax.grid(True, which="both", lw=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2])
