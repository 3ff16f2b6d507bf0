#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pane_sim.py BTDFTAB: a pane's system (btdftab albedo --back, model full: adding-doubling
of the two faces, docs/pane.md) against the goniophotometer of the same pane (btdftab
simulate --back: two explicit rough surfaces, every order, docs/simulation.md): T and R
per incident angle, light on either face, smooth and rough backs, with and without
absorption; and the outgoing distribution in simulate's bins.

Tolerance of T and R: 2e-2 of the incident power plus 4 standard errors of the simulation. The
model full matches the explicit surface within 1e-2 of the flux at every angle and
roughness (docs/model.md section 12), and a transmitted path crosses a rough face at
least twice (and a trapped one more, each time weighted less); the adding-doubling
itself is within 2e-3 of a finer one (tests/test_pane.c). Measured on these cases:
|difference| at most 1.4e-2 (s = 1, flat back, 30 degrees; 1.3e-2 at s = 3, flat back,
60 degrees, 5.6 standard errors). The seed is the tool's default; the cases are every
one measured for this check, none left out.
"""
import json
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
         (3.0, "smooth", 0.0, "back")]
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
    # 1e6 rays) against the system at the bins' centres, by e_L1 of MODEL.md section 6
    # over the bins (sum of |f - rho_sim| cos_sr, over max(T or R, 0.01)). Pure noise
    # gives e_L1 = floor = sqrt(2/pi) sum(rho_se cos_sr) / max(T or R, 0.01), the mean of
    # |N(0, se)|; over some 800 bins that sum wanders by about 3 % (1.1 is 3 of those),
    # and the model's own share is full's 2e-2 as above (it covers a bin's mean against
    # its centre too: the lobes at s = 3 span tens of degrees, the bins 2 by 10). So
    # e_L1 <= 1.1 floor + 2e-2. Eq. 25's pane (xu-sun) at 60 degrees must fail it.
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
            q = "".join("%s %s %s\n" % (r[ix["theta_i_deg"]], r[ix["theta_o_deg"]],
                                        r[ix["phi_deg"]]) for r in rr)
            f = [float(x) for x in subprocess.run(
                [tool, "eval", "--back", back, "-s", repr(s), "--ior", "1.5", "--thickness",
                 "4", "--absorption", repr(a), "--light", light, "--model", model, "--part",
                 part], input=q, check=True, capture_output=True, text=True).stdout.split()]
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
