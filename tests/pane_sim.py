#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pane_sim.py BTDFTAB: a pane's system (btdftab albedo --back, model full: adding-doubling
of the two faces, docs/pane.md) against the goniophotometer of the same pane (btdftab
simulate --back: two explicit rough surfaces, every order, docs/simulation.md): T and R
per incident angle, light on either face, smooth and rough backs, with and without
absorption; and the outgoing distribution in simulate's bins.

Tolerance of T and R: 2e-2 of the incident power plus 4 standard errors of the simulation.
Light entering from air, the model full matches the explicit surface within 1e-2 of the
flux at every angle and roughness (docs/model.md section 12), and a transmitted path
crosses a rough face at least twice (and a trapped one more, each time weighted less);
the adding-doubling itself is within 2e-3 of a finer one (tests/test_pane.c). Measured
on these cases: |difference| at most 1.4e-2 (s = 1, flat back, 30 degrees; 1.3e-2 at
s = 3, flat back, 60 degrees, 5.6 standard errors). The seed is the tool's default.
Not held to the bound: s = 1 with a flat back between 40 and 50 degrees, where T departs
by up to 3.0e-2 (16 standard errors; docs/pane.md, "Where the pane departs from the
surface"): the light the flat back traps meets the rough front again and again from the
glass, the side where full's interface itself departs by up to 3.3e-2 at s <= 1.5
(docs/model.md section 12).
"""
import json
import math
import os
import subprocess
import sys
import tempfile

tool = sys.argv[1]
passed = failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok %d - %s" % (passed, what))
    else:
        failed += 1
        print("not ok - %s" % what)
    sys.stdout.flush()


ANGLES = (0, 30, 60)
# (front s, back, absorption per mm, light)
CASES = [(1.0, "smooth", 0.0, "front"), (3.0, "smooth", 0.0, "front"),
         (10.0, "smooth", 0.0, "front"), (1.0, "3", 0.0, "front"), (3.0, "3", 0.02, "front"),
         (3.0, "smooth", 0.0, "back"), (10.0, "10", 0.0, "back")]
with tempfile.TemporaryDirectory() as w:
    for s, back, a, light in CASES:
        rep = os.path.join(w, "r.json")
        subprocess.run([tool, "simulate", "-q", "--ior", "1.5", "-s", repr(s), "--back", back,
                        "--thickness", "4", "--absorption", repr(a), "--light", light,
                        "--theta-i", ",".join(map(str, ANGLES)), "--rays", "200000",
                        "--report", rep], check=True)
        r = json.load(open(rep))
        out = subprocess.run([tool, "albedo", "--back", back, "-s", repr(s), "--ior", "1.5",
                              "--thickness", "4", "--absorption", repr(a), "--model", "full",
                              "--digits", "17"] + [str(x) for x in ANGLES],
                             check=True, capture_output=True, text=True).stdout
        rows = [l.split(",") for l in out.splitlines() if l and l[0].isdigit()]
        col = 1 if light == "front" else 4  # T_front, R_front, ... T_back, R_back
        worst = 0.0
        good = len(rows) == len(ANGLES)
        for k, row in enumerate(rows):
            T, R = float(row[col]), float(row[col + 1])
            for got, want, se in ((T, r["T"][k], r["T_se"][k]), (R, r["R"][k], r["R_se"][k])):
                tol = 2e-2 + 4.0 * se
                worst = max(worst, abs(got - want) / tol)
                good &= abs(got - want) <= tol
        check(good, "pane s = %g, back %s, a = %g/mm, light on the %s: T and R of model full "
              "against simulate at %s deg (2e5 rays): worst %.2f of the bound; T %s against "
              "%s" % (s, back, a, light, ",".join(map(str, ANGLES)), worst,
                      [round(float(x[col]), 4) for x in rows], [round(x, 4) for x in r["T"]]))

    # The outgoing distribution: simulate's histograms (45 x 18 bins of theta_o and |phi|,
    # 2 by 10 degrees, 1e6 rays) against the system's mean over each bin (4 x 5
    # sub-cells: at s = 10 the lobes are some 10 degrees wide, and the value at a bin's
    # centre differed from its mean by e_L1 0.06 there), by e_L1 of MODEL.md section 6
    # over the bins (sum of |f - rho_sim| cos_sr, over max(T or R, 0.01)). Pure noise
    # gives e_L1 = floor = sqrt(2/pi) sum(rho_se cos_sr) / max(T or R, 0.01), the mean of
    # |N(0, se)|; over some 800 bins that sum wanders by about 3 % (1.1 is 3 of those),
    # and the model's own share is full's 2e-2 as above. So e_L1 <= 1.1 floor + 2e-2.
    # Eq. 25's pane (xu-sun) at 60 degrees must fail it. Not held to it, and why
    # (docs/pane.md, "Where the pane departs from the surface"): s = 1 with a flat back
    # (e_L1 0.15 against a floor of 0.03 at 45 degrees) and grazing light at s = 10 (0.05
    # against 0.015 at 70 degrees), where full's interface itself departs as much from
    # the explicit surface (0.13 and 0.03 on the same bins, one face alone).
    NT, NP, DT, DP = 4, 5, 2.0, 10.0

    def dist(s, back, a, light, ti, model):
        path = os.path.join(w, "d.csv")
        subprocess.run([tool, "simulate", "-q", "--ior", "1.5", "-s", repr(s), "--back", back,
                        "--thickness", "4", "--absorption", repr(a), "--light", light,
                        "--theta-i", str(ti), "--rays", "1000000", "-o", path], check=True)
        hdr = open(path).readline().strip().split(",")
        ix = {h: i for i, h in enumerate(hdr)}
        rows = [l.strip().split(",") for l in open(path) if l[0].isdigit()]
        out = []
        for part in ("transmission", "reflection"):
            rr = [r for r in rows if r[ix["part"]] == part]
            # the system's mean over each bin (simulate's rho is a bin mean), by the
            # midpoint rule on NT x NP sub-cells weighted by |cos t| sin t
            q, wt = [], []
            for r in rr:
                t, p = float(r[ix["theta_o_deg"]]), float(r[ix["phi_deg"]])
                for i in range(NT):
                    tt = t - 0.5 * DT + (i + 0.5) * DT / NT
                    for j in range(NP):
                        q.append("%s %r %r\n" % (r[ix["theta_i_deg"]], tt,
                                                 p - 0.5 * DP + (j + 0.5) * DP / NP))
                        wt.append(abs(math.cos(math.radians(tt)) * math.sin(math.radians(tt))))
            fs = [float(x) for x in subprocess.run(
                [tool, "eval", "--back", back, "-s", repr(s), "--ior", "1.5", "--thickness",
                 "4", "--absorption", repr(a), "--light", light, "--model", model, "--part",
                 part], input="".join(q), check=True, capture_output=True,
                text=True).stdout.split()]
            k = NT * NP
            f = [sum(a * b for a, b in zip(fs[i * k:(i + 1) * k], wt[i * k:(i + 1) * k])) /
                 sum(wt[i * k:(i + 1) * k]) for i in range(len(fs) // k)]
            sim = [float(r[ix["rho"]]) for r in rr]
            se = [float(r[ix["rho_se"]]) for r in rr]
            cs = [float(r[ix["cos_sr"]]) for r in rr]
            norm = max(sum(x * c for x, c in zip(sim, cs)), 0.01)
            l1 = sum(abs(x - y) * c for x, y, c in zip(f, sim, cs)) / norm
            floor = (2.0 / 3.141592653589793) ** 0.5 * sum(x * c for x, c in zip(se, cs)) / norm
            out.append((part, l1, floor, len(rr) == len(f)))
        return out

    for s, back, a, light, ti, model, want in ((3.0, "smooth", 0.0, "front", 30, "full", True),
                                               (3.0, "3", 0.02, "back", 60, "full", True),
                                               (10.0, "smooth", 0.0, "front", 45, "full", True),
                                               (3.0, "smooth", 0.0, "front", 60, "xu-sun", False)):
        res = dist(s, back, a, light, ti, model)
        within = all(ok and l1 <= 1.1 * fl + 2e-2 for _, l1, fl, ok in res)
        check(within == want, "distribution, pane s = %g, back %s, a = %g/mm, light on the %s "
              "at %g deg, model %s against simulate (1e6 rays): %s; %s"
              % (s, back, a, light, ti, model, "; ".join(
                  "%s e_L1 %.4f, noise floor %.4f" % (p, l1, fl) for p, l1, fl, _ in res),
                  "within 1.1 floor + 2e-2" if want else "rejected, as it must be"))
print("%d passed, %d failed" % (passed, failed))
sys.exit(1 if failed or passed == 0 else 0)
