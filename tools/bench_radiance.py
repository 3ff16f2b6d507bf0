# SPDX-License-Identifier: MIT
"""bench_radiance.py BTDFTAB [OUTDIR [GROUPS]]: btdftab's Radiance BSDF files against Radiance's own
bsdf2ttree (-t3 -g 5/6/7) and bsdf2klems, all given Eq. 25 (n = 1.5, s = 3, k0 = 0.7),
side by side in one run. Needs pyradiance (Radiance's programs and BSDF library).

For each file: wall time to make it, size, and e_L1 (MODEL.md 6) of what Radiance's own
BSDF query returns, for light entering (from -Z, index n) and leaving (from +Z, 1/n):
  e_L1(ti) = sum |f_file - rho| pi / N / max(T(ti), 0.01)
over N = 96 x 96 view directions stratified in projected solid angle (midpoints in r^2,
phi), at 17 incident angles 2.5, 7.5, ..., 82.5 deg (light azimuth 17 deg), T by the same
sum over Eq. 25. The query takes the block of the view's side with the view as incident
(radiance.h), so the .cal function gives rho for light from its second vector to its
first. Prints a table: wall and CPU seconds (the children's user + system time) of one
run each on a shared machine, not medians; the file's size and the bytes of its
"Transmission Back" block (the one block bsdf2ttree writes for this function, light
entering), so that files with more blocks compare fairly. GROUPS: a comma list of
"radiance" (bsdf2ttree, bsdf2klems), "btdftab" (its three trees and its Klems file) and
"btdftab-klems" (its Klems file alone) (default "radiance,btdftab").
"""
import re
import resource
import math
import os
import subprocess
import sys
import time

import numpy as np
import pyradiance
from pyradiance import bsdf

N_IOR, S, K0 = 1.5, 3.0, 0.7

CAL = """{ Xu & Sun (2008) Eq. 25, MODEL.md section 2: rho for light arriving from (ox,oy,oz)
  and leaving along (ix,iy,iz), both pointing away from the surface; index n for light
  from -Z (entering), 1/n from +Z. }
n : %.17g; s : %.17g; k0 : %.17g;
PI : 3.14159265358979323846;
sq(x) : x*x;
sg(x) : if(x, 1, -1);
Vsh(c) : if(1 - c*c - 1e-12, exp(-(k0/s)*sqrt(1-c*c)/c*exp(-s*s*c*c/(4*(1-c*c)))), 1);
Ft(m, ca, cb) : 2*m*ca*cb*(1/sq(ca + m*cb) + 1/sq(m*ca + cb));
r4(m, ci, co, len2, vz2, ca, cb) : ca*Ft(m, ca, cb)*s*s*exp(-s*s*(len2 - vz2)/vz2/4)/(4*PI)
        *sq(len2/vz2)*m*m*cb/len2*Vsh(ci)*Vsh(co)/(ci*co);
r3(m, ci, co, len2, vz, cal, cbl) : if(cal, if(cbl, if(ci - 1e-9, if(co - 1e-9,
        if(746*vz*vz - .25*s*s*(len2 - vz*vz),
        r4(m, ci, co, len2, vz*vz, cal/sqrt(len2), cbl/sqrt(len2)), 0), 0), 0), 0), 0);
r2(m, vx, vy, vz, ex, ey, ez, fx, fy, fz) : r3(m, ez, -fz, vx*vx + vy*vy + vz*vz, vz,
        sg(vz)*(ex*vx + ey*vy + ez*vz), -sg(vz)*(fx*vx + fy*vy + fz*vz));
rho(m, ex, ey, ez, fx, fy, fz) : r2(m, ex + m*fx, ey + m*fy, ez + m*fz, ex, ey, ez, fx, fy, fz);
rough(ix, iy, iz, ox, oy, oz) : if(-iz*oz, if(-oz, rho(n, ox, oy, -oz, ix, iy, -iz),
        rho(1/n, ox, oy, oz, ix, iy, iz)), 0);
""" % (N_IOR, S, K0)


def rbin(name):
    return os.path.join(os.path.dirname(pyradiance.__file__), "bin", name)


def rho(m, ti, to, phi):
    """Eq. 25 (MODEL.md 2), vectorised over to and phi; light in the upper medium."""
    ei = np.array([math.sin(ti), 0.0, math.cos(ti)])
    eo = np.stack([np.sin(to) * np.cos(phi), np.sin(to) * np.sin(phi), np.cos(to)], axis=-1)
    v = ei + m * eo
    len2 = (v * v).sum(-1)
    sg = np.where(v[..., 2] < 0, -1.0, 1.0)
    ca = sg * (v @ ei) / np.sqrt(len2)
    cb = -sg * (eo * v).sum(-1) / np.sqrt(len2)
    vz2 = v[..., 2] ** 2
    ok = (ca > 0) & (cb > 0) & (0.25 * S * S * (len2 - vz2) < 746 * vz2)
    with np.errstate(all="ignore"):
        t2 = (len2 - vz2) / vz2
        D = S * S * np.exp(-0.25 * S * S * t2) / (4 * math.pi) * (len2 / vz2) ** 2
        ft = 2 * m * ca * cb * (1 / (ca + m * cb) ** 2 + 1 / (m * ca + cb) ** 2)
        chi = m * m * cb / len2

        def V(c):
            c = np.abs(c)
            tn = np.sqrt(np.maximum(0, 1 - c * c)) / np.maximum(c, 1e-300)
            return np.where(tn > 0, np.exp(-(K0 * tn / S) * np.exp(-S * S / (4 * np.maximum(tn, 1e-300) ** 2))), 1.0)

        r = ca * ft * D * chi * V(math.cos(ti)) * V(np.cos(to)) / (math.cos(ti) * np.abs(np.cos(to)))
    return np.where(ok, r, 0.0)


def e_l1(xml):
    sd = bsdf.load_file(xml)
    nr = nphi = 96
    r = np.sqrt((np.arange(nr) + 0.5) / nr)
    ph = 2 * np.pi * (np.arange(nphi) + 0.5) / nphi
    R, P = np.meshgrid(r, ph, indexing="ij")
    R, P = R.ravel(), P.ravel()
    to = math.pi - np.arcsin(np.minimum(R, 1.0))  # the view in the light's frame
    az_p = np.degrees(P)
    out = {}
    for side, m, lz in (("enter", N_IOR, -1), ("leave", 1 / N_IOR, 1)):
        es = []
        for ti_deg in np.arange(2.5, 85, 5.0):
            ti, az_q = math.radians(ti_deg), 17.0
            th_q = ti_deg if lz > 0 else 180 - ti_deg  # Radiance's polar angles
            th_p = np.degrees(to) if lz > 0 else 180 - np.degrees(to)
            f = np.array([bsdf.query(sd, a, b, th_q, az_q)[1] for a, b in zip(th_p, az_p)])
            tru = rho(m, ti, to, np.radians(az_p - az_q))
            T = tru.sum() * math.pi / len(P)
            es.append(np.abs(f - tru).sum() * math.pi / len(P) / max(T, 0.01))
        out[side] = (max(es), float(np.mean(es)))
    return out


def block_bytes(xml, label="Transmission Back"):
    """Bytes of the ScatteringData of the block with that WavelengthDataDirection."""
    text = open(xml, encoding="utf-8", errors="replace").read()
    for blk in re.findall(r"<WavelengthDataBlock>(.*?)</WavelengthDataBlock>", text, re.S):
        if re.search(r"<WavelengthDataDirection>\s*%s\s*<" % label, blk):
            m = re.search(r"<ScatteringData>(.*?)</ScatteringData>", blk, re.S)
            return len(m.group(1).encode()) if m else 0
    return 0


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd, out_path, cwd):
    t0 = time.time()
    if out_path.endswith(".xml") and "btdftab" in os.path.basename(cmd[0]):
        subprocess.run(cmd, check=True, cwd=cwd)
    else:
        with open(out_path, "wb") as f:
            subprocess.run(cmd, check=True, stdout=f, cwd=cwd)
    return time.time() - t0


def main():
    btdftab = os.path.abspath(sys.argv[1])
    wd = os.path.abspath(sys.argv[2] if len(sys.argv) > 2 else "bench-radiance")
    os.makedirs(wd, exist_ok=True)
    with open(os.path.join(wd, "rough.cal"), "w") as f:
        f.write(CAL)
    env_path = os.path.dirname(rbin("bsdf2ttree"))
    os.environ["PATH"] = env_path + os.pathsep + os.environ["PATH"]
    os.environ["RAYPATH"] = ".:" + os.path.join(os.path.dirname(pyradiance.__file__), "lib")
    groups = (sys.argv[3] if len(sys.argv) > 3 else "radiance,btdftab").split(",")
    jobs = []
    for g in (5, 6, 7) if "radiance" in groups else ():
        jobs.append(("bsdf2ttree -t3 -g %d" % g,
                     [rbin("bsdf2ttree"), "-t3", "-g", str(g), "-f", "rough.cal", "rough"],
                     "b2t_g%d.xml" % g))
    if "radiance" in groups:
        jobs.append(("bsdf2klems", [rbin("bsdf2klems"), "-f", "rough.cal", "rough"], "b2k.xml"))
    for tol in (0.5, 0.2, 0.1) if "btdftab" in groups else ():
        jobs.append(("btdftab tree3 --tolerance %g" % tol,
                     [btdftab, "tabulate", "-q", "--basis", "tree3", "--tolerance", str(tol),
                      "-o", "bt_t%g.xml" % tol], "bt_t%g.xml" % tol))
    if "btdftab" in groups or "btdftab-klems" in groups:
        jobs.append(("btdftab klems-full",
                     [btdftab, "tabulate", "-q", "--basis", "klems-full", "-o", "bt_kf.xml"],
                     "bt_kf.xml"))
    rows = []
    for name, cmd, out in jobs:
        path = os.path.join(wd, out)
        c0 = cpu_children()
        secs = run(cmd, path, wd)
        cpu = cpu_children() - c0
        e = e_l1(path)
        bb = block_bytes(path)
        rows.append((name, secs, cpu, os.path.getsize(path), bb, e))
        print("%-30s %8.1f s %8.1f CPU-s %10d B (block %d B)  e_L1 enter max %.3g mean %.3g; "
              "leave max %.3g mean %.3g" %
              (name, secs, cpu, os.path.getsize(path), bb, e["enter"][0], e["enter"][1],
               e["leave"][0], e["leave"][1]), flush=True)
    print("\n| tool | wall (s) | CPU (s) | file (bytes) | Transmission Back (bytes) | "
          "e_L1 entering max / mean | e_L1 leaving max / mean |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, secs, cpu, size, bb, e in rows:
        print("| %s | %.1f | %.1f | %d | %d | %.3g / %.3g | %.3g / %.3g |" %
              (name, secs, cpu, size, bb, e["enter"][0], e["enter"][1], e["leave"][0],
               e["leave"][1]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
