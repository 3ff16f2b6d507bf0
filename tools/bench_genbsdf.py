# SPDX-License-Identifier: MIT
"""Compare Radiance's genBSDF with btdftab on one frosted glass pane.

The pane: glass of relative index n (default 1.5) in air, a rough front face
(a Gaussian random surface of smoothness s = correlation length / RMS height,
default 3, so an RMS slope of 2/s), a flat back face, no absorption.

What the script does:

1. Generates a periodic Gaussian random height field z(x, y) with the
   autocorrelation C(r) = h^2 exp(-r^2 / l^2), l = s h, on an N x N grid by FFT
   filtering of white noise with a fixed seed, and prints its RMS height and
   the RMS slope of its triangles (by default the heights are then scaled so
   that the triangles' RMS slope is exactly 2/s: in geometric optics only the
   slopes matter).
2. Writes the pane as a Radiance scene: the height field as a triangle mesh
   (obj2mesh) of `dielectric` glass, tiled K x K times (genBSDF has no periodic
   boundaries: the tiles stand in for a laterally infinite pane), the rough
   face on the -Z side with its normals pointing down, out of the glass, and the
   flat face at the top (z just below 0) with its normal up; black walls around
   the tiled patch absorb the light that travels inside the glass beyond it,
   so that it shows as lost energy instead of landing in a wrong direction.
   genBSDF's convention (its manual page): the device lies behind z = 0, +Z
   points into the room, and the "front" of the LBNL/WINDOW XML it writes is
   the exterior, -Z side. So the rough face is the XML's front, the same side
   btdftab's pane files give to the rough face (Radiance's -Z side).
3. Runs genBSDF (pyradiance's genBSDF, `pyradiance.generate_bsdf` and
   `pyradiance.generate_xml`) for the Klems full basis, sampling over one
   tile (`-dim`), for one or more sample counts, and times it.
4. Runs btdftab for the same pane (`tabulate --back smooth --basis klems-full`
   with `--model full` and with the default model xu-sun, plus the default
   tree3 basis of each, timed) and `btdftab albedo --back smooth --model full`.
5. Reads the four Klems blocks of each XML, computes the hemispherical T and R
   per incident patch (sum over outgoing patches of f times the patch's
   projected solid angle) and prints them at incident patches whose theta
   centre is 0, 30, 60 and 82.5 degrees, next to btdftab's albedo averaged over
   the same band; an e_L1-like difference of the matrices per incident patch;
   Radiance's own hemispherical query of each file (pyradiance.bsdf) as a
   check of the parsing; and the machine and the times.

Run it in a Python environment with numpy and pyradiance installed:

    python3 bench_genbsdf.py BTDFTAB OUTDIR [--run 2000] [--run 2000@0.37]
        [--run "2000:-lr -100"] [--nproc 2]

Each --run C[@SHIFT][:OPTS] is one genBSDF run: C samples per incident patch
(genBSDF's -c), the sampling window moved by SHIFT tiles in x and y (the same
periodic surface, other ray samples: two runs differing only in SHIFT measure
the Monte Carlo noise; genBSDF's sampling is otherwise deterministic) and OPTS
extra rcontrib options (genBSDF's -r; rcontrib's default reflection limit is
-lr -10). Default: one run, --run 2000.

BTDFTAB is the path of the btdftab executable, OUTDIR a folder for the files
(created if missing). `--help` lists the other options (grid, tile size,
thickness, tiling, seed). Lengths in the scene are in micrometres.
"""

import argparse
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np

# Klems full basis: (lower theta, upper theta, number of azimuth patches)
KLEMS_FULL = [(0, 5, 1), (5, 15, 8), (15, 25, 16), (25, 35, 20), (35, 45, 24),
              (45, 55, 24), (55, 65, 24), (65, 75, 16), (75, 90, 12)]
BLOCKS = ["Transmission Front", "Reflection Front",
          "Transmission Back", "Reflection Back"]
# bands reported: theta centres 0, 30, 60 and 82.5 degrees
REPORT_BANDS = [0, 3, 6, 8]


# ----------------------------------------------------------------- small functions

def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


class Timer:
    """Wall clock and the CPU time of child processes over a block."""

    def __enter__(self):
        self.w0 = time.perf_counter()
        self.c0 = children_cpu()
        self.s0 = time.process_time()
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self.w0
        self.cpu_children = children_cpu() - self.c0
        self.cpu_self = time.process_time() - self.s0
        return False


def run(cmd, **kw):
    print("$ " + " ".join(str(c) for c in cmd), flush=True)
    return subprocess.run([str(c) for c in cmd], check=True, **kw)


def klems_geometry(bands=KLEMS_FULL):
    """Per patch: projected solid angle, theta centre, band index, phi centre."""
    om, th, band, phi = [], [], [], []
    for b, (lo, hi, nphi) in enumerate(bands):
        w = np.sin(np.radians(hi)) ** 2 - np.sin(np.radians(lo)) ** 2
        for k in range(nphi):
            om.append(np.pi * w / nphi)
            th.append(0.0 if lo == 0 else 0.5 * (lo + hi))
            band.append(b)
            phi.append(360.0 * k / nphi)
    return np.array(om), np.array(th), np.array(band), np.array(phi)


def parse_klems(path):
    """The Klems blocks of an LBNL XML file, as f[out, in] in 1/sr."""
    txt = open(path, encoding="utf-8", errors="replace").read()
    inc = re.search(r"<IncidentDataStructure>\s*(\w+)\s*<", txt)
    inc = inc.group(1) if inc else "Columns"
    # the file's own basis, to check that it is the standard full basis
    bands = []
    for m in re.finditer(r"<AngleBasisBlock>(.*?)</AngleBasisBlock>", txt, re.S):
        blk = m.group(1)
        lo = re.search(r"<LowerTheta>\s*([-\d.eE+]+)", blk)
        hi = re.search(r"<UpperTheta>\s*([-\d.eE+]+)", blk)
        nphi = re.search(r"<nPhis>\s*(\d+)", blk)
        if lo and hi and nphi:
            bands.append((float(lo.group(1)), float(hi.group(1)), int(nphi.group(1))))
    blocks = {}
    for m in re.finditer(r"<WavelengthData>(.*?)</WavelengthData>", txt, re.S):
        wd = m.group(1)
        lam = re.search(r"<Wavelength\b[^>]*>\s*([\w-]+)\s*<", wd)
        if lam and lam.group(1).lower() != "visible":
            continue
        for mb in re.finditer(r"<WavelengthDataBlock>(.*?)</WavelengthDataBlock>", wd, re.S):
            blk = mb.group(1)
            d = re.search(r"<WavelengthDataDirection>\s*(.*?)\s*<", blk)
            sd = re.search(r"<ScatteringData>(.*?)</ScatteringData>", blk, re.S)
            if not d or not sd:
                continue
            v = np.array(sd.group(1).replace(",", " ").split(), dtype=float)
            n = int(round(np.sqrt(v.size)))
            v = v.reshape(n, n)
            # "Columns": each text row is one outgoing patch, its entries the
            # incident patches (Radiance's bsdf_m.c reads value[out * n + in])
            blocks[d.group(1)] = v if inc.lower() == "columns" else v.T
    return blocks, inc, bands


def hemispherical(f, om):
    """T (or R) per incident patch: sum_o f[o, i] Omega_proj(o)."""
    return (f * om[:, None]).sum(axis=0)


def e_l1(fa, fb, om):
    """Per incident patch: sum_o |fa - fb| Omega_proj(o) / max(Tb, 0.01)."""
    tb = hemispherical(fb, om)
    return (np.abs(fa - fb) * om[:, None]).sum(axis=0) / np.maximum(tb, 0.01)


# ----------------------------------------------------------------- surface

def make_surface(n_grid, l_over_dx, s, h, seed):
    """Periodic Gaussian random heights with C(r) = h^2 exp(-r^2 / l^2)."""
    l = s * h
    dx = l / l_over_dx
    rng = np.random.default_rng(seed)
    w = rng.standard_normal((n_grid, n_grid))
    k = 2 * np.pi * np.fft.fftfreq(n_grid, d=dx)
    k2 = k[:, None] ** 2 + k[None, :] ** 2
    filt = np.exp(-k2 * l * l / 8.0)       # |filt|^2 = exp(-k^2 l^2 / 4)
    z = np.real(np.fft.ifft2(np.fft.fft2(w) * filt))
    # ensemble variance of z for unit white noise: mean of |filt|^2
    z *= h / np.sqrt(np.mean(filt ** 2))
    return z, dx, l


def facet_slopes(z, dx):
    """Gradients of the two triangles of every cell (periodic grid)."""
    z10 = np.roll(z, -1, axis=0)            # x + dx (axis 0 is x)
    z01 = np.roll(z, -1, axis=1)            # y + dx
    z11 = np.roll(z10, -1, axis=1)
    # triangle A: (00, 10, 11); triangle B: (00, 11, 01)
    gxa, gya = (z10 - z) / dx, (z11 - z10) / dx
    gxb, gyb = (z11 - z01) / dx, (z01 - z) / dx
    gx = np.concatenate([gxa.ravel(), gxb.ravel()])
    gy = np.concatenate([gya.ravel(), gyb.ravel()])
    return gx, gy


def write_obj(path, z, dx, z0):
    """The tile as an OBJ mesh at z0 + z, normals pointing -Z (down)."""
    n = z.shape[0]
    with open(path, "w") as f:
        f.write("# periodic Gaussian rough face, one tile, normals -Z\n")
        for i in range(n + 1):
            for j in range(n + 1):
                f.write("v %.9g %.9g %.9g\n" % (i * dx, j * dx, z0 + z[i % n, j % n]))
        def vid(i, j):
            return i * (n + 1) + j + 1
        for i in range(n):
            for j in range(n):
                a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
                # clockwise seen from +Z: the right-hand normal points to -Z
                f.write("f %d %d %d\nf %d %d %d\n" % (a, c, b, a, d, c))


def write_scene(path, rtm, tile, k_tiles, z_top, z_bot, ior):
    """Tiled rough face, flat top face and absorbing walls."""
    half = k_tiles // 2
    x0, x1 = -half * tile, (half + 1) * tile
    with open(path, "w") as f:
        f.write("void dielectric glass\n0\n0\n5 1 1 1 %g 0\n\n" % ior)
        f.write("void plastic black\n0\n0\n5 0 0 0 0 0\n\n")
        for i in range(-half, half + 1):
            for j in range(-half, half + 1):
                f.write("glass mesh tile.%d.%d\n5 %s -t %.9g %.9g 0\n0\n0\n\n"
                        % (i + half, j + half, rtm, i * tile, j * tile))
        # flat back face, counter-clockwise seen from +Z: normal +Z (out of the glass)
        f.write("glass polygon flat_face\n0\n0\n12\n")
        for x, y in [(x0, x0), (x1, x0), (x1, x1), (x0, x1)]:
            f.write("\t%.9g %.9g %.9g\n" % (x, y, z_top))
        f.write("\n")
        # walls around the tiled patch, from below the rough face to the flat face
        corners = [(x0, x0), (x1, x0), (x1, x1), (x0, x1)]
        for w in range(4):
            (xa, ya), (xb, yb) = corners[w], corners[(w + 1) % 4]
            f.write("black polygon wall.%d\n0\n0\n12\n" % w)
            for x, y, zz in [(xa, ya, z_bot), (xb, yb, z_bot), (xb, yb, z_top), (xa, ya, z_top)]:
                f.write("\t%.9g %.9g %.9g\n" % (x, y, zz))
            f.write("\n")
    return x0, x1


# ----------------------------------------------------------------- main

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("btdftab", help="path of the btdftab executable")
    ap.add_argument("outdir", help="folder for the scene, the XML files and the log")
    ap.add_argument("--ior", type=float, default=1.5)
    ap.add_argument("--smoothness", "-s", type=float, default=3.0)
    ap.add_argument("--rms-height", type=float, default=10.0,
                    help="RMS height h in micrometres (default 10)")
    ap.add_argument("--grid", type=int, default=256, help="N, grid points per side of a tile")
    ap.add_argument("--l-over-dx", type=float, default=8.0,
                    help="correlation length over grid spacing (default 8: tile = N/8 l)")
    ap.add_argument("--thickness", type=float, default=10.0,
                    help="glass thickness in units of h (default 10)")
    ap.add_argument("--tiles", type=int, default=21, help="K, tiles per side (odd)")
    ap.add_argument("--seed", type=int, default=12345, help="seed of the height field")
    ap.add_argument("--no-normalize", action="store_true",
                    help="keep the heights as drawn (do not scale the RMS slope to 2/s)")
    ap.add_argument("--run", action="append", metavar="C[@SHIFT][:OPTS]",
                    help="one genBSDF run (repeatable): -c C, window shifted by SHIFT "
                         "tiles, extra rcontrib options OPTS")
    ap.add_argument("--nproc", type=int, default=2, help="genBSDF -n")
    ap.add_argument("--skip-tree3", action="store_true", help="do not build btdftab's tree3 files")
    args = ap.parse_args()
    plan = []
    for spec in (args.run or ["2000"]):
        head, _, opts = spec.partition(":")
        c, _, shift = head.partition("@")
        plan.append((int(c), float(shift or 0.0), opts.strip()))

    import pyradiance as pr
    import pyradiance.bsdf as prb
    from pyradiance.genbsdf import SamplingBox

    out = os.path.abspath(args.outdir)
    # The script writes files of fixed names (tile.obj, pane.rad, the XML files) into
    # OUTDIR: it takes a new or empty folder, or one it made before (its marker file), so
    # that it never writes over someone's files.
    marker = os.path.join(out, ".bench_genbsdf")
    if os.path.isdir(out) and os.listdir(out) and not os.path.exists(marker):
        sys.exit("bench_genbsdf.py: %s: give a new or empty folder (it holds files this "
                 "script did not make)" % out)
    os.makedirs(out, exist_ok=True)
    open(marker, "a").close()
    btdftab = os.path.abspath(args.btdftab)
    times = []

    print("== machine")
    print("CPU: %s; cores (os.cpu_count): %s; load average at start: %s"
          % (cpu_model(), os.cpu_count(), " ".join("%.2f" % x for x in os.getloadavg())))
    print("Python %s, numpy %s, pyradiance %s" % (platform.python_version(), np.__version__,
                                                  getattr(pr, "__version__", "?")))
    print("Radiance binaries: %s" % pr.anci.BINPATH)

    # ---------------- surface
    s, h = args.smoothness, args.rms_height
    z, dx, l = make_surface(args.grid, args.l_over_dx, s, h, args.seed)
    tile = args.grid * dx
    gx, gy = facet_slopes(z, dx)
    slope = np.sqrt(np.mean(gx ** 2 + gy ** 2))
    print("\n== surface")
    print("N = %d, l = s h = %g um, grid spacing %g um = l/%g, tile L = %g um = %g l, seed %d"
          % (args.grid, l, dx, args.l_over_dx, tile, tile / l, args.seed))
    print("drawn: RMS height %.4f um (target h = %g), mean %.2e; RMS slope of the triangles "
          "%.4f (target 2/s = %.4f; x %.4f, y %.4f, target sqrt(2)/s = %.4f each)"
          % (np.std(z), h, np.mean(z), slope, 2 / s, np.sqrt(np.mean(gx ** 2)),
             np.sqrt(np.mean(gy ** 2)), np.sqrt(2) / s))
    # the continuous field's RMS slope seen through triangles of side dx: forward
    # differences, var = 2 h^2 (1 - exp(-dx^2/l^2)) / dx^2 per axis
    disc = np.sqrt(2 * 2 * h * h * (1 - np.exp(-dx * dx / (l * l))) / (dx * dx))
    print("expected RMS slope of triangles of a Gaussian field of RMS slope 2/s at this "
          "spacing: %.4f" % disc)
    if not args.no_normalize:
        f = (2 / s) / slope
        z *= f
        gx, gy = facet_slopes(z, dx)
        print("scaled heights by %.4f: RMS height %.4f um, RMS slope %.4f (x %.4f, y %.4f)"
              % (f, np.std(z), np.sqrt(np.mean(gx ** 2 + gy ** 2)),
                 np.sqrt(np.mean(gx ** 2)), np.sqrt(np.mean(gy ** 2))))
    z -= np.mean(z)
    thick = args.thickness * h
    margin = 0.01                               # um, keeps genBSDF's senders off the faces
    z_top = -margin                             # flat face, just below z = 0
    z_rough = z_top - thick                     # mean plane of the rough face
    z_min = z_rough + z.min()
    print("heights span %.3f .. %.3f um around the mean; thickness %g um (%g h); "
          "rough face mean plane z = %g, flat face z = %g"
          % (z.min(), z.max(), thick, args.thickness, z_rough, z_top))

    # ---------------- scene
    obj = os.path.join(out, "tile.obj")
    rtm = os.path.join(out, "tile.rtm")
    write_obj(obj, z, dx, z_rough)
    with Timer() as t:
        run([os.path.join(pr.anci.BINPATH, "obj2mesh"), obj, rtm])
    print("obj2mesh: %d triangles per tile, %.1f s" % (2 * args.grid ** 2, t.wall))
    scene = os.path.join(out, "pane.rad")
    x0, x1 = write_scene(scene, rtm, tile, args.tiles, z_top, z_min - 1.0, args.ior)
    print("scene %s: %d x %d tiles, x and y over [%g, %g] um (%.0f thicknesses from the "
          "sampled tile to the walls)" % (scene, args.tiles, args.tiles, x0, x1,
                                          (args.tiles // 2) * tile / thick))
    # check the orientation: a ray from below, along +Z, into the rough face, and one
    # from above into the flat face: each must refract (dielectric), not stop
    oct_ = os.path.join(out, "pane.oct")
    with open(oct_, "wb") as fo:
        run([os.path.join(pr.anci.BINPATH, "oconv"), scene], stdout=fo)
    probe = ("%g %g %g 0 0 1\n%g %g %g 0 0 -1\n"
             % (0.37 * tile, 0.61 * tile, z_min - 5, 0.37 * tile, 0.61 * tile, 5))
    r = subprocess.run([os.path.join(pr.anci.BINPATH, "rtrace"), "-h", "-oodNnm", oct_],
                       input=probe.encode(), stdout=subprocess.PIPE, check=True)
    print("orientation probe (rtrace -oodNnm: origin, direction, surface normal, perturbed "
          "normal, modifier) for a ray up into the rough face and one down into the flat "
          "face; the normal must point back along each ray (out of the glass):")
    for line in r.stdout.decode().split("\n"):
        if line.strip():
            print("  " + line.strip())

    # ---------------- genBSDF
    om, th, band, phi = klems_geometry()
    gen_runs, run_key = [], {}
    for c, shift, opts in plan:
        extra = opts.split()
        label = "genBSDF -c %d%s%s" % (c, " -r '%s'" % opts if opts else "",
                                       " @%g" % shift if shift else "")
        dim = SamplingBox(shift * tile, (1 + shift) * tile, shift * tile, (1 + shift) * tile,
                          z_min - margin, 0.0)
        print("\n== %s -n %d" % (label, args.nproc))
        print("-dim %g %g %g %g %g %g" % tuple(dim))
        with Timer() as t:
            res = pr.generate_bsdf(scene, nsamp=c, nproc=args.nproc, dim=dim,
                                   params=extra or None)
            xml = pr.generate_xml(vis_results=res, basis="kf", unit="meter")
        name = "genbsdf_c%d%s%s.xml" % (c, "_" + re.sub(r"[^\w.-]+", "", opts) if opts else "",
                                         "_at%g" % shift if shift else "")
        path = os.path.join(out, name)
        with open(path, "wb") as fo:
            fo.write(xml)
        print("%s: wall %.1f s, CPU (children) %.1f s, this process %.1f s -> %s"
              % (label, t.wall, t.cpu_children, t.cpu_self, path))
        times.append((label + " -n %d" % args.nproc, t.wall, t.cpu_children + t.cpu_self, path))
        gen_runs.append((label, path))
        run_key[label] = (c, shift, opts)

    # ---------------- btdftab
    common = ["--back", "smooth", "-s", "%g" % s, "--ior", "%g" % args.ior,
              "--thickness", "%g" % (thick / 1000.0)]
    bt = {}
    jobs = [("full", "klems-full"), ("xu-sun", "klems-full")]
    if not args.skip_tree3:
        jobs += [("full", "tree3"), ("xu-sun", "tree3")]
    print("\n== btdftab")
    for model, basis in jobs:
        path = os.path.join(out, "btdftab_%s_%s.xml" % (model, basis))
        cmd = [btdftab, "tabulate"] + common + ["--model", model, "--basis", basis, "-o", path]
        with Timer() as t:
            run(cmd)
        label = "btdftab tabulate --model %s --basis %s" % (model, basis)
        print("%s: wall %.1f s, CPU %.1f s" % (label, t.wall, t.cpu_children))
        times.append((label, t.wall, t.cpu_children, path))
        bt[(model, basis)] = path

    # albedo: band centres and 8 Gauss-Legendre nodes in w = sin^2(theta) per band
    gl_x, gl_w = np.polynomial.legendre.leggauss(8)
    angles, weights = {}, {}
    for b in REPORT_BANDS:
        lo, hi, _ = KLEMS_FULL[b]
        wlo, whi = np.sin(np.radians(lo)) ** 2, np.sin(np.radians(hi)) ** 2
        wn = 0.5 * (whi + wlo) + 0.5 * (whi - wlo) * gl_x
        angles[b] = np.degrees(np.arcsin(np.sqrt(wn)))
        weights[b] = gl_w / 2.0
    centres = [0.0 if KLEMS_FULL[b][0] == 0 else 0.5 * (KLEMS_FULL[b][0] + KLEMS_FULL[b][1])
               for b in REPORT_BANDS]
    all_angles = list(centres) + [a for b in REPORT_BANDS for a in angles[b]]
    alb = {}
    for model in ["full", "xu-sun"]:
        with Timer() as t:
            r = run([btdftab, "albedo"] + common + ["--model", model, "--digits", "8"]
                    + ["%.10g" % a for a in all_angles], stdout=subprocess.PIPE)
        rows = [ln.split(",") for ln in r.stdout.decode().split("\n")
                if ln and ln[0].isdigit()]
        vals = np.array([[float(x) for x in row[1:]] for row in rows])
        alb[model] = vals      # columns: T_front, R_front, R+T_front, T_back, R_back, R+T_back
        print("btdftab albedo --model %s (%d angles): wall %.2f s" % (model, len(all_angles), t.wall))

    def albedo_band(model, b, col):
        v = alb[model]
        k = len(centres) + REPORT_BANDS.index(b) * len(gl_x)
        return float(np.dot(weights[b], v[k:k + len(gl_x), col]))

    def albedo_centre(model, b, col):
        return float(alb[model][REPORT_BANDS.index(b), col])

    # ---------------- compare
    files = [(lab, p) for lab, p in gen_runs]
    files += [("btdftab full", bt[("full", "klems-full")]),
              ("btdftab xu-sun", bt[("xu-sun", "klems-full")])]
    data = {}
    print("\n== files")
    for lab, p in files:
        blocks, inc, bands = parse_klems(p)
        ok = (len(bands) == 0 or
              [(round(a, 3), round(b_, 3), n) for a, b_, n in bands] ==
              [(float(a), float(b_), n) for a, b_, n in KLEMS_FULL])
        print("%-40s IncidentDataStructure %s, blocks %s, basis %s, %d bytes"
              % (lab, inc, ", ".join(sorted(blocks)), "LBNL/Klems Full (checked)" if ok
                 else "DIFFERENT: %s" % bands, os.path.getsize(p)))
        missing = [b_ for b_ in BLOCKS if b_ not in blocks]
        if missing:
            print("  missing blocks: %s" % missing)
        data[lab] = blocks

    # block -> (albedo column, meaning)
    meaning = {"Transmission Front": (0, "T, light on the -Z side (rough face)"),
               "Reflection Front": (1, "R, light on the -Z side (rough face)"),
               "Transmission Back": (3, "T, light on the +Z side (flat face)"),
               "Reflection Back": (4, "R, light on the +Z side (flat face)")}
    print("\n== hemispherical T and R per incident band (mean over the band's patches; "
          "genBSDF +- the standard error of that mean from the spread between the band's "
          "patches, and the spread itself)")
    print("albedo: btdftab albedo --model full (or xu-sun) averaged over the band in "
          "projected solid angle (8 Gauss nodes in sin^2 theta); 'at centre' at the band's "
          "theta centre only")
    for blk in BLOCKS:
        col, what = meaning[blk]
        print("\n%s  (%s)" % (blk, what))
        print("%-44s" % "source" + "".join("| %-25s" % ("theta %g" % c_) for c_ in centres))
        for lab, _ in files:
            if blk not in data[lab]:
                print("%-44s| missing" % lab)
                continue
            tt = hemispherical(data[lab][blk], om)
            line = "%-44s" % lab
            for b in REPORT_BANDS:
                v = tt[band == b]
                if lab.startswith("genBSDF") and v.size > 1:
                    line += "| %.4f +-%.4f (sd %.4f) " % (v.mean(), v.std(ddof=1) / np.sqrt(v.size),
                                                          v.std(ddof=1))
                else:
                    line += "| %-25s" % ("%.4f" % v.mean())
            print(line)
        for lab, fn in [("albedo full, band average", albedo_band),
                        ("albedo full, at the band centre", albedo_centre)]:
            print("%-44s" % lab + "".join("| %-25s" % ("%.4f" % fn("full", b, col))
                                          for b in REPORT_BANDS))
        print("%-44s" % "albedo xu-sun, band average" +
              "".join("| %-25s" % ("%.4f" % albedo_band("xu-sun", b, col)) for b in REPORT_BANDS))

    print("\n== block mapping: for each genBSDF block, the RMS difference (over the four "
          "bands above) from btdftab's albedo of light on the rough face and on the flat face")
    for lab, _ in gen_runs[:1]:
        for blk in BLOCKS:
            if blk not in data[lab]:
                continue
            tt = hemispherical(data[lab][blk], om)
            g = np.array([tt[band == b].mean() for b in REPORT_BANDS])
            part = 0 if blk.startswith("Transmission") else 1
            dr = np.sqrt(np.mean([(g[k] - albedo_band("full", b, part)) ** 2
                                  for k, b in enumerate(REPORT_BANDS)]))
            df = np.sqrt(np.mean([(g[k] - albedo_band("full", b, part + 3)) ** 2
                                  for k, b in enumerate(REPORT_BANDS)]))
            print("  %s %-19s vs %s on the rough face %.4f, on the flat face %.4f -> %s"
                  % (lab, blk, "T" if part == 0 else "R", dr, df,
                     "rough face" if dr < df else "flat face"))
    print("lobe alignment: outgoing patch (theta, phi) of the largest entry, incident patch "
          "(theta, phi 0) of each band, genBSDF's first run / btdftab full")
    for blk in BLOCKS:
        cells = []
        for b in REPORT_BANDS[1:]:
            i = int(np.flatnonzero(band == b)[0])
            o = []
            for lab in (gen_runs[0][0], "btdftab full"):
                if blk in data[lab]:
                    j = int(np.argmax(data[lab][blk][:, i]))
                    o.append("(%g,%g)" % (th[j], phi[j]))
            cells.append("in (%g,0): %s" % (th[i], " / ".join(o)))
        print("  %-19s %s" % (blk, "   ".join(cells)))

    print("\n== R + T per side (energy; 1 for a lossless pane; genBSDF below 1 by light "
          "absorbed in the walls, cut by rcontrib's reflection limit -lr or its weight limit)")
    for side in ["Front", "Back"]:
        print("%s (light on the %s side):" % (side, "-Z, rough" if side == "Front" else "+Z, flat"))
        for lab, _ in files:
            d = data[lab]
            if "Transmission " + side not in d or "Reflection " + side not in d:
                continue
            tot = hemispherical(d["Transmission " + side], om) + hemispherical(d["Reflection " + side], om)
            print("  %-40s %s   min %.4f (theta %g), all-patch mean %.4f"
                  % (lab, "  ".join("%g:%.4f" % (c_, tot[band == b].mean())
                                    for b, c_ in zip(REPORT_BANDS, centres)),
                     tot.min(), th[np.argmin(tot)], tot.mean()))

    print("\n== e_L1 per incident patch: sum_o |f_a - f_b| Omega_proj(o) / max(X_b, 0.01), "
          "X_b = b's hemispherical T or R of that patch; max (theta of the worst patch) and "
          "median over the 145 patches, and over the patches up to 75 degrees")
    ref = "btdftab full"
    pairs = [(lab, ref) for lab, _ in gen_runs] + [("btdftab xu-sun", ref)]
    pairs += [(lab, "btdftab xu-sun") for lab, _ in gen_runs[:1]]
    # genBSDF against genBSDF: runs that differ only in the window (Monte Carlo noise:
    # divide by sqrt(2) for one run's floor), or in C or the options
    for i in range(len(gen_runs)):
        for j in range(i + 1, len(gen_runs)):
            pairs.append((gen_runs[j][0], gen_runs[i][0]))
    for a, b_ in pairs:
        print("%s  vs  %s" % (a, b_))
        for blk in BLOCKS:
            if blk not in data[a] or blk not in data[b_]:
                continue
            e = e_l1(data[a][blk], data[b_][blk], om)
            e75 = e[th <= 75]
            print("  %-19s max %.4f (theta %g)  median %.4f  | <=75 deg: max %.4f median %.4f"
                  % (blk, e.max(), th[np.argmax(e)], np.median(e), e75.max(), np.median(e75)))
    print("(two genBSDF runs that differ only in the window '@': their e_L1 is about sqrt(2) "
          "times one run's Monte Carlo floor)")

    print("\n== Radiance's own hemispherical query (pyradiance.bsdf.direct_hemi; "
          "theta < 90: a direction on +Z, theta > 90: on -Z, phi 0): T (flags T|S|D) and "
          "R (R|S|D), one patch of a Klems file, a point of a tree")
    qfiles = files + ([("btdftab full tree3", bt[("full", "tree3")]),
                       ("btdftab xu-sun tree3", bt[("xu-sun", "tree3")])]
                      if not args.skip_tree3 else [])
    TF = prb.SAMPLE_T | prb.SAMPLE_SP | prb.SAMPLE_DF
    RF = prb.SAMPLE_R | prb.SAMPLE_SP | prb.SAMPLE_DF
    print("%-32s %s" % ("file", "  ".join("%-17s" % ("-Z %g T/R" % c_) for c_ in centres)
                        + "  " + "  ".join("%-17s" % ("+Z %g T/R" % c_) for c_ in centres)))
    for lab, p in qfiles:
        sd = prb.load_file(p)
        cells = []
        for side in (-1, 1):
            for c_ in centres:
                tq = c_ if side > 0 else 180.0 - c_
                cells.append("%.4f/%.4f" % (prb.direct_hemi(sd, tq, 0.0, TF),
                                            prb.direct_hemi(sd, tq, 0.0, RF)))
        print("%-32s %s" % (lab[:32], "  ".join("%-17s" % c_ for c_ in cells)))

    print("\n== times (wall clock; CPU = user + system of the processes it ran)")
    for lab, wall, cpu, p in times:
        print("  %-58s wall %8.1f s   CPU %8.1f s   %9d bytes" % (lab, wall, cpu, os.path.getsize(p)))
    print("load average at the end: %s" % " ".join("%.2f" % x for x in os.getloadavg()))


if __name__ == "__main__":
    main()
