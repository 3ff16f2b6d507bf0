# SPDX-License-Identifier: MIT
"""radiance_check.py FILE.xml REPORT.json: reads a btdftab Radiance BSDF with Radiance's own
library and programs (the pyradiance wheel) and checks it against btdftab's report.

1. The file loads, with both transmission blocks and both reflection blocks (every
   basis, tree or Klems, holds the four), and the report lists the four.
2. At the report's 1,000 probes per block (light and view directions in Radiance's
   frame), Radiance's BSDF query returns the value the report says the file holds.
   Tolerance, relative, plus 1e-6 absolute: tree 2e-4: Radiance stores values as float
   (relative 6e-8) and multiplies each tree value by 1 + 1e-4 d with |d| <= 1.5, a
   position-dependent perturbation (its bsdf_t.c), so 1.5e-4 is the most it may move.
   Klems 5e-4: Radiance multiplies each matrix value by 1 + 6e-4 (d - 0.5), 0 <= d < 1
   (bsdf_m.c), at most 3e-4; measured up to 3.0e-4 (one channel) and 3.6e-4 (colour,
   whose Y also passes through Radiance's 4-digit "sharp RGB" matrices).
   A colour file (Klems, CIE X, Y, Z): Y as above; X and Z within what Radiance's
   colour representation allows: it keeps Y and the chromaticity (u', v'), each of
   these in 8 bits (steps of 1/410, rounded up or down at random: ccolor.c), so a
   decoded u', v' is within 1/410 of the file's; the allowance is the largest change of
   X (Z) over that square around the file's u', v', plus 5e-4 X (Z).
   A colour tree (Y, u', v' trees): Radiance keeps u', v' as floats and forms the colour
   from the perturbed Y and u', v' through its "sharp" RGB: to sharp RGB with one
   4-digit matrix (T) and back with another (F), which are not exact inverses, so it
   returns F T (X, Y, Z) (1 + 1e-4 d) (bsdf_t.c, ccolor.c). X, Y and Z each within 2e-4
   relative (plus 1e-6) of F T times the file's X, Y, Z (as the report reads them).
3. rtrace with a BSDF material, lit by a distant source on the side of the light a block
   serves and viewed from the block's own side (Radiance takes the block of the view's
   side) along N directions stratified in projected solid angle, gives
   the hemispherical transmittance T(ti) = sum L pi / N / (E_sun cos ti) (for a
   reflection block, viewed from the light's side: the reflectance R(ti)). It must match
   the report's T (R) within the report's e_T at that angle (times max(T, 0.01)) plus
   twice the change of the sum between N and N/4 directions (the quadrature's own
   error) plus twice the change of the report's own estimate of the file's integral
   between its density and a quarter of it (T_file against T_file_coarse: that estimate
   is a stratified sum too). The angle: the report's nearest 30 degrees that has both
   estimates. R and T each within their errors put R + T within the sum of the two.
   A colour file: each of rtrace's R, G, B against that channel's T, with in addition
   the bound of what Radiance's colour representation can lose in the sum (the (u', v')
   square of check 2 at every view, summed, plus 5e-4 of the channel); and the loss
   itself is measured: the sum of the file's own R, G, B over the same views (read
   from the file's X, Y, Z by Radiance's Klems index rule) against rtrace's, which must
   lie within that bound. A colour tree: the bound is that of check 2's F T summed, i.e.
   per channel sum_j |A_cj| T_j + 1.5e-4 (T_c + sum_j |A_cj| T_j), A = C (F T - I) M (M
   the report's RGB -> XYZ, C its inverse, T_j the report's estimate of the file's
   channel j, raised by twice its own estimate error); the loss is measured against the
   report's own estimate of the file's channel (T_file), within that bound plus the two
   sums' own errors (2 x quadrature + 2 x estimate).
Prints one "ok"/"not ok" line per check and ends with "N passed, N failed".
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
import pyradiance
from pyradiance import bsdf

passed = 0
failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok %d - %s" % (passed + failed, what))
    else:
        failed += 1
        print("not ok %d - %s" % (passed + failed, what))


def rbin(name):
    return os.path.join(os.path.dirname(pyradiance.__file__), "bin", name)


def radiance_env():
    env = dict(os.environ)
    lib = os.path.join(os.path.dirname(pyradiance.__file__), "lib")
    env["RAYPATH"] = ".:" + lib
    return env


def rtrace(octree, opts, rays, cwd):
    inp = "".join("%.9g %.9g %.9g %.9g %.9g %.9g\n" % tuple(r) for r in rays)
    out = subprocess.run([rbin("rtrace"), "-h", "-ov"] + opts + [octree], input=inp,
                         capture_output=True, text=True, cwd=cwd, env=radiance_env(),
                         check=True).stdout
    return np.array([[float(x) for x in line.split()] for line in out.splitlines() if line.strip()])


def view_dirs(nr, nphi, up):
    """Directions over the hemisphere on the side `up` (+1/-1), each standing for
    projected solid angle pi / (nr nphi): midpoints in r^2 and phi."""
    r = np.sqrt((np.arange(nr) + 0.5) / nr)
    ph = 2 * np.pi * (np.arange(nphi) + 0.5) / nphi
    R, P = np.meshgrid(r, ph, indexing="ij")
    x, y = (R * np.cos(P)).ravel(), (R * np.sin(P)).ravel()
    z = up * np.sqrt(np.maximum(0.0, 1 - x * x - y * y))
    return np.stack([x, y, z], axis=1)


# Radiance's "sharp" RGB matrices (ccolor.c, float): XYZ -> sharp (T) and back (F).
SHARP_TO = np.array([[1.2694, -0.0988, -0.1706], [-0.8364, 1.8006, 0.0357],
                     [0.0297, -0.0315, 1.0018]], dtype=np.float32).astype(float)
SHARP_FROM = np.array([[0.8156, 0.0472, 0.1372], [0.3791, 0.5769, 0.0440],
                       [-0.0123, 0.0167, 0.9955]], dtype=np.float32).astype(float)


# Radiance's Klems bases by name (bsdf_m.c): theta bounds (degrees) and patches per band.
KLEMS = {"klems-full": ([0, 5, 15, 25, 35, 45, 55, 65, 75, 90], [1, 8, 16, 20, 24, 24, 24, 16, 12]),
         "klems-half": ([0, 6.5, 19.5, 32.5, 45.5, 58.5, 71.5, 90], [1, 8, 12, 16, 20, 12, 8]),
         "klems-quarter": ([0, 9, 27, 45, 63, 90], [1, 8, 12, 12, 8])}


def klems_patch(basis, theta, phi):
    """Radiance's patch of a direction (degrees): its theta band, round(phi nphi / 360)."""
    tb, nphi = KLEMS[basis]
    if not 0 <= theta < 90:
        return -1
    band, first = 0, 0
    while band + 1 < len(nphi) and tb[band + 1] <= theta:
        first += nphi[band]
        band += 1
    j = int((phi % 360.0) * nphi[band] / 360.0 + 0.5)
    return first + (0 if j >= nphi[band] else j)


def klems_matrices(xml):
    """{(wavelength, block label): matrix values as one array} of a Klems file."""
    ns = {"w": "http://windows.lbl.gov"}
    out = {}
    for wd in ET.parse(xml).getroot().iter("{http://windows.lbl.gov}WavelengthData"):
        wl = wd.find("w:Wavelength", ns).text.strip()
        for b in wd.findall("w:WavelengthDataBlock", ns):
            lab = b.find("w:WavelengthDataDirection", ns).text.strip()
            txt = b.find("w:ScatteringData", ns).text.replace(",", " ")
            out[(wl, lab)] = np.array([float(x) for x in txt.split()])
    return out


def klems_xyz(mats, basis, label, p, q):
    """The file's X, Y, Z at view p (incident, as Radiance reads it) and light q."""
    n = sum(KLEMS[basis][1])
    i = klems_patch(basis, math.degrees(math.acos(min(1.0, abs(p[2])))),
                    math.degrees(math.atan2(-p[1], -p[0])))
    o = klems_patch(basis, math.degrees(math.acos(min(1.0, abs(q[2])))),
                    math.degrees(math.atan2(q[1], q[0])))
    if i < 0 or o < 0:
        return np.zeros(3)
    e = o * n + i
    return np.array([mats[(w, label)][e] for w in ("CIE-X", "Visible", "CIE-Z")])


def chroma_box(xyz, lin):
    """The largest change of lin @ XYZ when the chromaticity (u', v') of xyz moves by up to
    1/410 in each (Radiance's 8-bit encoding), Y fixed: per row of lin."""
    X, Y, Z = xyz
    s = X + 15 * Y + 3 * Z
    if Y <= 0 or s <= 0:
        return np.zeros(lin.shape[0])
    u, v = 4 * X / s, 9 * Y / s
    base = lin @ xyz
    worst = np.zeros(lin.shape[0])
    d = 1.0 / 410
    for du in (-d, 0, d):
        for dv in (-d, 0, d):
            uu, vv = u + du, v + dv
            if vv <= 0:
                continue
            x2 = Y * 9 * uu / (4 * vv)
            z2 = Y * (12 - 3 * uu - 20 * vv) / (4 * vv)
            worst = np.maximum(worst, np.abs(lin @ np.array([x2, Y, z2]) - base))
    return worst


def main():
    xml, rep_path = os.path.abspath(sys.argv[1]), sys.argv[2]
    rep = json.load(open(rep_path))
    sd = bsdf.load_file(xml)
    nrefl = sum(1 for b in rep["blocks"] if b.get("reflection"))
    check(sd is not None and sd.tf is not None and sd.tb is not None and
          sd.rf is not None and sd.rb is not None and
          len(rep["blocks"]) == 4 and nrefl == 2,
          "Radiance loads %s with both transmission blocks and both reflection blocks "
          "(%s basis; the report lists %d blocks, %d of them reflection)" %
          (os.path.basename(xml), rep["basis"], len(rep["blocks"]), nrefl))
    tree = rep["basis"] == "tree3"
    rel = 2e-4 if tree else 5e-4
    colour = len(rep["ior"]) == 3
    xz = np.array([[1.0, 0, 0], [0, 0, 1.0]])
    FT = SHARP_FROM @ SHARP_TO
    for blk in rep["blocks"]:
        bad, worst, nonzero, badc, worst_xz, used_xz = 0, 0.0, 0, 0, 0.0, 0.0
        for pr in blk["probes"]:
            ts, ps, tv, pv, v = pr[:5]
            got = bsdf.query(sd, ts, ps, tv, pv)  # X, Y, Z; light direction first
            y = float(got[1])
            nonzero += v > 0
            # a colour tree's Y passes through F T too: that change allowed on top
            shift = abs(float((FT - np.eye(3))[1] @ np.array([pr[6], v, pr[7]]))) \
                if colour and tree else 0.0
            if abs(y - v) > rel * v + shift + 1e-6:
                bad += 1
            worst = max(worst, abs(y - v) / max(v, 1e-30))
            if colour and tree:
                want = FT @ np.array([pr[6], v, pr[7]])
                diff = np.abs(np.asarray(got, dtype=float) - want)
                allow = 2e-4 * np.abs(want) + 1e-6
                badc += int(np.any(diff > allow))
                if v > 1e-3:
                    worst_xz = max(worst_xz, float(np.max(diff / np.abs(want))))
                    used_xz = max(used_xz, float(np.max(diff / allow)))
            elif colour:
                fx, fz = pr[6], pr[7]
                allow = chroma_box(np.array([fx, v, fz]), xz) + 5e-4 * np.array([fx, fz]) + 1e-6
                diff = np.abs(np.array([got[0], got[2]]) - np.array([fx, fz]))
                badc += int(np.any(diff > allow))
                if v > 1e-3:
                    worst_xz = max(worst_xz, float(np.max(diff / np.array([fx, fz]))))
                    used_xz = max(used_xz, float(np.max(diff / allow)))
        check(bad == 0 and nonzero >= 100,
              "%s: Radiance's query equals the report at %d probes (%d non-zero; worst "
              "relative difference %.2g)" % (blk["label"], len(blk["probes"]), nonzero, worst))
        if colour and tree:
            check(badc == 0,
                  "%s: Radiance's X, Y, Z equal its sharp-RGB round trip F T of the file's "
                  "(Y, u', v') at %d probes (worst relative difference %.2g where Y > 1e-3; "
                  "at most %.2f of the allowance 2e-4)"
                  % (blk["label"], len(blk["probes"]), worst_xz, used_xz))
        elif colour:
            check(badc == 0,
                  "%s: Radiance's X and Z within its (u', v') encoding of the file's at %d "
                  "probes (worst relative difference %.2g where Y > 1e-3; at most %.2f of "
                  "the allowance)" % (blk["label"], len(blk["probes"]), worst_xz, used_xz))

    work = tempfile.mkdtemp()
    mats = klems_matrices(xml) if colour and not tree else None
    to_rgb = np.linalg.inv(np.array(rep["rgb_to_xyz"])) if colour else None
    # a colour tree: channel c's change through F T per unit of channel j
    A = np.abs(to_rgb @ (FT - np.eye(3)) @ np.array(rep["rgb_to_xyz"])) if colour else None
    for blk in rep["blocks"]:
        light_side = -1.0 if blk["side"] == "enter" else 1.0  # Front: light from -Z
        view_side = light_side if blk.get("reflection") else -light_side
        # (name, per-angle rows, rtrace column): a grey file's R = G = B, so G alone
        chans = ([(ch["channel"], ch["per_theta_i"], c) for c, ch in enumerate(blk["channels"])]
                 if colour else [("", blk["per_theta_i"], 1)])
        rows = [e for e in chans[0][1] if e.get("T_file_coarse") is not None]
        ang = min(rows, key=lambda e: abs(e["theta_i_deg"] - 30.0))["theta_i_deg"]
        ti = math.radians(ang)
        sun = (math.sin(ti) * math.cos(0.3), math.sin(ti) * math.sin(0.3),
               light_side * math.cos(ti))
        with open(os.path.join(work, "sun.rad"), "w") as f:
            f.write("void light solar 0 0 3 1000 1000 1000\n"
                    "solar source sun 0 0 4 %.12g %.12g %.12g 0.5\n" % sun)
        with open(os.path.join(work, "pane.rad"), "w") as f:
            f.write("void BSDF glz 6 0 %s 0 1 0 . 0 0\n"
                    "glz polygon pane 0 0 12 -1e4 -1e4 0 1e4 -1e4 0 1e4 1e4 0 -1e4 1e4 0\n" % xml)
        for name, files in (("sun.oct", ["sun.rad"]), ("scene.oct", ["sun.rad", "pane.rad"])):
            with open(os.path.join(work, name), "wb") as f:
                subprocess.run([rbin("oconv")] + files, stdout=f, cwd=work, check=True,
                               env=radiance_env())
        direct = ["-ab", "0", "-dv-", "-ss", "0", "-st", "1", "-av", "0", "0", "0", "-dj", "0",
                  "-ds", "0", "-dt", "0", "-dc", "1", "-lr", "1", "-lw", "0"]
        e_sun = rtrace("sun.oct", ["-I"] + direct, [(0, 0, 0) + sun], work)[0, 1]
        sums = []
        for nr, nphi in ((64, 128), (128, 256)):
            v = view_dirs(nr, nphi, view_side)
            rays = [(x * 1e-3, y * 1e-3, view_side * 1.0, -x, -y, -z) for x, y, z in v]
            L = rtrace("scene.oct", direct, rays, work)
            sums.append(L.sum(axis=0) * math.pi / len(v) / (e_sun * math.cos(ti)))
        if colour and tree:
            at = [[e for e in ch["per_theta_i"] if e["theta_i_deg"] == ang][0]
                  for ch in blk["channels"]]
            tj = np.array([e["T_file"] + 2 * abs(e["T_file"] - e["T_file_coarse"]) for e in at])
            own = np.array([e["T_file"] for e in at])
            bound = A @ tj + 1.5e-4 * (tj + A @ tj)
        elif colour:
            # the file's own R, G, B over the same 128 x 256 views, and the bound of what
            # Radiance's (u', v') encoding can change in each (per matrix entry, cached)
            own, bound, cache = np.zeros(3), np.zeros(3), {}
            for p in v:
                xyz = klems_xyz(mats, rep["basis"], blk["label"], p, sun)
                key = tuple(xyz)
                if key not in cache:
                    c = to_rgb @ xyz
                    cache[key] = (c, chroma_box(xyz, to_rgb) + 5e-4 * np.abs(c))
                own += cache[key][0]
                bound += cache[key][1]
            own *= math.pi / len(v)
            bound *= math.pi / len(v)
        what = "reflectance" if blk.get("reflection") else "transmittance"
        for name, per_list, col in chans:
            per = [e for e in per_list if e["theta_i_deg"] == ang][0]
            e_t = per["e_t"]  # the report's e_T at this very angle
            t_rt, quad = sums[1][col], abs(sums[1][col] - sums[0][col])
            T = per["T"]
            est = abs(per["T_file"] - per["T_file_coarse"])
            tol = e_t * max(T, 0.01) + 2 * quad + 2 * est
            label = blk["label"] + (" " + name if name else "")
            extra = ""
            if colour and tree:
                tol += bound[col]
                extra = " + colour %.2g" % bound[col]
                loss = abs(t_rt - own[col])
                allow = bound[col] + 2 * quad + 2 * est
                check(loss <= allow,
                      "%s: rtrace %s at %.2f deg %.5f vs the report's estimate of the "
                      "file's %.5f: |diff| %.2g (%.2g relative) <= colour %.2g + 2 x "
                      "quadrature %.2g + 2 x estimate %.2g"
                      % (label, what, ang, t_rt, own[col], loss, loss / max(own[col], 1e-30),
                         bound[col], quad, est))
            elif colour:
                tol += bound[col]
                extra = " + colour %.2g" % bound[col]
                loss = abs(t_rt - own[col])
                check(loss <= bound[col],
                      "%s: rtrace %s at %.2f deg %.5f vs the file's own %.5f: Radiance's "
                      "colour representation lost %.2g (%.2g relative) <= its bound %.2g"
                      % (label, what, ang, t_rt, own[col], loss, loss / max(own[col], 1e-30),
                         bound[col]))
            check(abs(t_rt - T) <= tol,
                  "%s: rtrace %s at %.2f deg %.5f vs %s %.5f (|diff| %.2g <= e_T %.3g "
                  "x max(T, 0.01) + 2 x quadrature %.2g + 2 x estimate %.2g%s)"
                  % (label, what, ang, t_rt, "R" if blk.get("reflection") else "T", T,
                     abs(t_rt - T), e_t, quad, est, extra))
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
