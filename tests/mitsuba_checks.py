# SPDX-License-Identifier: MIT
"""Checks of the Mitsuba 3 plugin `btdftab` (python/btdftab_mitsuba), run by
tests/mitsuba.sh in a venv with mitsuba from PyPI:

    python tests/mitsuba_checks.py VARIANT TABLE_DIR [--render OUT_DIR] [--render-only]
        [--repeats N]

TABLE_DIR holds the tables tests/mitsuba.sh writes with btdftab. Prints one "ok" or
"not ok" line per check, the measured figures, and "N passed, N failed" last.
"""
import json
import math
import os
import random
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

VARIANT, TABLES = sys.argv[1], sys.argv[2]
RENDER_DIR = sys.argv[sys.argv.index("--render") + 1] if "--render" in sys.argv else None
REPEATS = int(sys.argv[sys.argv.index("--repeats") + 1]) if "--repeats" in sys.argv else 3
RENDER_ONLY = "--render-only" in sys.argv  # the timing of docs/mitsuba3.md
mi.set_variant(VARIANT)
import btdftab_mitsuba  # noqa: E402  (registers the plugin)
from btdftab_mitsuba import libbtdf  # noqa: E402

JIT = dr.is_jit_v(mi.Float)
EPS32 = 2.0 ** -23
FLT_MIN = 2.0 ** -126
passed = failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok %d - %s" % (passed + failed, what))
    else:
        failed += 1
        print("not ok %d - %s" % (passed + failed, what))
    sys.stdout.flush()


def tab(name):
    return os.path.join(TABLES, name)


def bsdf(**kw):
    d = {"type": "btdftab"}
    d.update(kw)
    return mi.load_dict(d)


# ---------------------------------------------------------------------------------
# 1. eval equals btdf_table_eval at 10,000 random direction pairs, both sides
# ---------------------------------------------------------------------------------
def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def angles(a, b):
    """(ti, to, phi) of a (z > 0) and b (z < 0), both normalised in double."""
    a, b = unit(a), unit(b)
    ti = math.atan2(math.hypot(a[0], a[1]), a[2])
    to = math.atan2(math.hypot(b[0], b[1]), b[2])
    phi = math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])
    return ti, to, phi


def rho_ref(front, back, src, dst):
    """The physical BTDF for light arriving along src, leaving along dst, by libbtdf."""
    if src[2] > 0:
        return front.eval(*angles(src, dst))
    flip = lambda v: [v[0], v[1], -v[2]]  # noqa: E731
    if back is not None:
        return back.eval(*angles(flip(src), flip(dst)))
    # the plugin's documented rule: rho(1/n; src -> dst) = n^-2 rho~(n; dst -> src)
    return [v / (n * n) for v, n in zip(front.eval(*angles(dst, src)), front.ior)]


def rand_dir(rng, up):
    z = rng.uniform(1e-4, 1.0)
    p = rng.uniform(0.0, 2.0 * math.pi)
    r = math.sqrt(1.0 - z * z)
    return [r * math.cos(p), r * math.sin(p), z if up else -z]


def as_lists(vec):
    if JIT:
        return [list(zip(*(vec[i].numpy().tolist() for i in range(3))))]
    return [tuple(float(x) for x in vec)]


def eval_many(b, mode, wis, wos):
    """Plugin eval for lists of float32 directions; returns per pair a 3-list."""
    ctx = mi.BSDFContext(mode)
    if JIT:
        si = dr.zeros(mi.SurfaceInteraction3f, len(wis))
        si.wi = mi.Vector3f(*[[w[i] for w in wis] for i in range(3)])
        wo = mi.Vector3f(*[[w[i] for w in wos] for i in range(3)])
        v = b.eval(ctx, si, wo)
        return list(zip(*(v[c].numpy().tolist() for c in range(3))))
    out = []
    for a, c in zip(wis, wos):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(a)
        v = b.eval(ctx, si, mi.Vector3f(c))
        out.append((float(v[0]), float(v[1]), float(v[2])))
    return out


def sampled_dirs(b, wis, rng):
    """Directions in the lobe: drawn by the plugin's own sampler (only to place test
    points where rho is large; the values are checked against libbtdf)."""
    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    u = [(rng.random(), rng.random(), rng.random()) for _ in wis]
    if JIT:
        si = dr.zeros(mi.SurfaceInteraction3f, len(wis))
        si.wi = mi.Vector3f(*[[w[i] for w in wis] for i in range(3)])
        bs, _ = b.sample(ctx, si, mi.Float([x[0] for x in u]),
                         mi.Point2f([x[1] for x in u], [x[2] for x in u]))
        return [list(x) for x in zip(*(bs.wo[i].numpy().tolist() for i in range(3)))]
    out = []
    for a, x in zip(wis, u):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(a)
        bs, _ = b.sample(ctx, si, x[0], mi.Point2f(x[1], x[2]))
        out.append([float(t) for t in bs.wo])
    return out


def f32(v):
    return [float(x) for x in mi.ScalarVector3f(v)]


def eval_check(label, fname, back_name=None, pairs=10000, seed=1):
    front = libbtdf.Table(tab(fname))
    back = libbtdf.Table(tab(back_name)) if back_name else None
    kw = {"filename": tab(fname)}
    if back_name:
        kw["filename_back"] = tab(back_name)
    b = bsdf(**kw)
    rng = random.Random(seed)
    wis = [f32(rand_dir(rng, i % 2 == 0)) for i in range(pairs)]  # half from behind
    wos = [rand_dir(rng, w[2] < 0) for w in wis]
    lobe = sampled_dirs(b, wis[pairs // 2:], rng)  # the second half: in the lobe
    wos = [f32(w) for w in wos[:pairs // 2] + lobe]
    keep = [i for i in range(pairs) if wis[i][2] * wos[i][2] < 0]
    wis = [wis[i] for i in keep]
    wos = [wos[i] for i in keep]
    for mode, mname in ((mi.TransportMode.Importance, "importance"),
                        (mi.TransportMode.Radiance, "radiance")):
        got = eval_many(b, mode, wis, wos)
        # per side of the light's arrival: [front, back]
        max_abs, max_rel, peak = [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]
        bad = 0
        for a, c, g in zip(wis, wos, got):
            src, dst = (c, a) if mode == mi.TransportMode.Radiance else (a, c)
            side = 0 if src[2] > 0 else 1
            ref = rho_ref(front, back, src, dst)
            cw = abs(c[2])  # the plugin's |cos wo| = |wo.z|, as Mitsuba's own BSDFs take it
            for ch in range(3):
                r = ref[min(ch, len(ref) - 1)] * cw
                d = abs(g[ch] - r)
                peak[side] = max(peak[side], r)
                max_abs[side] = max(max_abs[side], d)
                if r >= FLT_MIN:
                    max_rel[side] = max(max_rel[side], d / r)
                # Two float roundings (rho, then rho |cos wo|) bound the difference by
                # eps32 |ref|; the factor 2 covers the double-precision paths differing
                # (the plugin works from vector components, libbtdf from angles).
                # Below FLT_MIN float flushes to zero.
                if d > 2.0 * EPS32 * r + FLT_MIN:
                    bad += 1
        check(bad == 0, "eval = btdf_table_eval, %s, %s mode, %d pairs; light from the "
              "front / from behind: max abs diff %.3g / %.3g, max rel diff %.3g / %.3g "
              "(values >= FLT_MIN), peak %.4g / %.4g; %d beyond 2 eps32 |ref| + FLT_MIN"
              % (label, mname, len(wis), max_abs[0], max_abs[1], max_rel[0], max_rel[1],
                 peak[0], peak[1], bad))
    if back is not None:
        # The back table is what answers from behind: it differs from the front table
        # read by reciprocity by the two tables' errors, not by nothing.
        one = bsdf(filename=tab(fname))
        idx = [i for i in range(len(wis)) if wis[i][2] < 0]
        w1 = [wis[i] for i in idx]
        w2 = [wos[i] for i in idx]
        v2 = eval_many(b, mi.TransportMode.Importance, w1, w2)
        v1 = eval_many(one, mi.TransportMode.Importance, w1, w2)
        d = max(abs(x[0] - y[0]) for x, y in zip(v1, v2)) / max(x[0] for x in v1)
        check(0.0 < d < 0.01, "light from behind: back table vs front table by reciprocity "
              "differ by max %.3g of the peak (nonzero: the back table is used)" % d)
    return b


def analytic_check(pairs=10000, seed=2):
    """Mode analytic against btdf_eval (Eq. 25 of libbtdf), both sides."""
    for n, s in ((1.5, 3.0), (1.0 / 1.5, 6.0), (1.5, 100.0)):
        b = bsdf(mode="analytic", ior=str(n), smoothness=s)
        p = libbtdf.make_params(n, s)
        pb = libbtdf.make_params(1.0 / n, s)
        rng = random.Random(seed)
        wis = [f32(rand_dir(rng, i % 2 == 0)) for i in range(pairs)]
        wos = [rand_dir(rng, w[2] < 0) for w in wis]
        lobe = sampled_dirs(b, wis[pairs // 2:], rng)
        wos = [f32(w) for w in wos[:pairs // 2] + lobe]
        got = eval_many(b, mi.TransportMode.Importance, wis, wos)
        max_rel = 0.0
        bad = 0
        for a, c, g in zip(wis, wos, got):
            if a[2] * c[2] >= 0:
                continue
            flip = lambda v: [v[0], v[1], -v[2]]  # noqa: E731
            ref = (libbtdf.rho(p, *angles(a, c)) if a[2] > 0
                   else libbtdf.rho(pb, *angles(flip(a), flip(c))))[0] * abs(c[2])
            d = abs(g[0] - ref)
            if ref >= FLT_MIN:
                max_rel = max(max_rel, d / ref)
            # Eq. 25 in double in both, then two float roundings; at s = 100 the lobe's
            # exponent s^2 tan^2/4 amplifies double rounding of the angles, measured < 1e-9.
            if d > 2.0 * EPS32 * ref + FLT_MIN:
                bad += 1
        check(bad == 0, "analytic mode = btdf_eval, n = %.4g, s = %g: max rel diff %.3g"
              % (n, s, max_rel))


# ---------------------------------------------------------------------------------
# 2. sampling: Mitsuba's chi-square test, and the mean weight against T(ti)
# ---------------------------------------------------------------------------------
# (table, n, s, incident angles): for n < 1 the angles stay below and near the critical
# angle (41.8 degrees), past which almost nothing is transmitted (T(60) = 0.026).
CASES = [("f15.exr", 1.5, 3.0, [0.0, 30.0, 60.0, 80.0]),
         ("f15s100.exr", 1.5, 100.0, [0.0, 30.0, 60.0, 80.0]),
         ("r066s6.exr", 1.0 / 1.5, 6.0, [0.0, 20.0, 40.0, 60.0])]


def wi_of(deg, side=1.0):
    t = math.radians(deg)
    return [math.sin(t), 0.0, side * math.cos(t)]


class ZoomDomain:
    """Directions within a cone around `center`, by gnomonic coordinates (x, y) in
    [-r, r]^2: w = normalize(x e1 + y e2 + center), d(omega) = dx dy / (1+x^2+y^2)^1.5.
    For s = 100 the lobe is about 0.4 degrees wide, below the sphere's 1.8-degree cells
    at res = 101, where the trapezoid rule cannot integrate the pdf over a cell."""

    def __init__(self, center, r):
        self.e3 = mi.ScalarVector3f(center)
        self.e1, self.e2 = mi.coordinate_system(self.e3)
        self.r = r

    def bounds(self):
        return mi.ScalarBoundingBox2f([-self.r, -self.r], [self.r, self.r])

    def aspect(self):
        return 1.0

    def map_forward(self, p):
        return dr.normalize(self.e1 * p.x + self.e2 * p.y + self.e3)

    def map_backward(self, w):
        l3 = dr.dot(w, self.e3)  # <= 0: far outside, flagged by the test as it should
        return mi.Vector2f(dr.dot(w, self.e1) / l3, dr.dot(w, self.e2) / l3)

    def wrap(self, sf, pf):
        def sample(u, *a):
            wo, w = sf(u, *a)
            # weight-0 samples add nothing to the histogram; put them inside the domain
            return dr.select(w > 0.0, wo, mi.Vector3f(self.e3)), w

        def pdf(w, *a):
            l3 = dr.dot(w, self.e3)
            return pf(w, *a) / (l3 * l3 * l3)  # (1+x^2+y^2)^-1.5 = l3^3 for unit w
        return sample, pdf


def chi2_one(fname, wi, zoom=None, distort=False):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain
    sf, pf = BSDFAdapter("btdftab", {"type": "btdftab", "filename": tab(fname)}, wi=wi)
    if distort:
        pf0 = pf
        pf = lambda w, *a: pf0(w, *a) * dr.select(w.y > 0.0, 1.1, 0.9)  # noqa: E731
    domain = SphericalDomain()
    if zoom is not None:
        domain = zoom
        sf, pf = zoom.wrap(sf, pf)
    chi = ChiSquareTest(domain=domain, sample_func=sf, pdf_func=pf, sample_dim=3,
                        sample_count=1000000, res=101, ires=8)
    return chi


def chi2_checks():
    ntests = sum(len(c[3]) for c in CASES) + 1
    for fname, n, s, angles_deg in CASES:
        for deg in angles_deg:
            wi = wi_of(deg)
            zoom = None
            if s > 50:  # the refracted direction of the mean surface, 0.15 rad around it
                st = math.sin(math.radians(deg)) / n
                zoom = ZoomDomain([-st, 0.0, -math.sqrt(1.0 - st * st)], 0.15)
            chi = chi2_one(fname, wi, zoom)
            ok = chi.run(0.01, test_count=ntests, quiet=True)
            check(ok, "chi2: n = %.4g, s = %g, ti = %g deg, p-value %.3g (1e6 samples, %s)%s"
                  % (n, s, deg, chi.p_value,
                     "101 x 101 cells over 0.15 rad around the refracted direction" if zoom
                     else "101 x 202 cells over the sphere",
                     "" if ok else ": " + chi.messages.strip()))
    # the other side of the (1.5, 3) table: light from behind, by reciprocity
    chi = chi2_one("f15.exr", wi_of(45.0, -1.0))
    ok = chi.run(0.01, test_count=ntests, quiet=True)
    check(ok, "chi2: n = 1.5 table seen from behind (n = 0.6667), s = 3, ti = 45 deg, "
          "p-value %.3g" % chi.p_value)
    # Negative controls: the same tests reject a pdf 10% off along one axis.
    for fname, s, zoom in (("f15.exr", 3.0, None),
                           ("f15s100.exr", 100.0, ZoomDomain(
                               [-0.5 / 1.5, 0.0, -math.sqrt(1.0 - 0.25 / 2.25)], 0.15))):
        chi = chi2_one(fname, wi_of(30.0), zoom, distort=True)
        ok = not chi.run(0.01, test_count=ntests, quiet=True)
        check(ok, "chi2 rejects a pdf distorted by 1 + 0.1 sign(x) (s = %g, ti = 30): "
              "p-value %.3g" % (s, chi.p_value))


def report_of(fname):
    with open(tab(fname[:fname.rindex(".")] + ".json")) as f:
        return json.load(f)


def weight_checks(count):
    """The mean of the sampled weight f |cos wo| / pdf estimates the integral of
    f |cos wo|: T(ti) in importance mode, T(ti)/n^2 in radiance mode."""
    for fname, n, s, angles_deg in CASES:
        e_t = report_of(fname)["e_t"]["max"]
        for deg in (angles_deg if JIT else angles_deg[1::2]):  # scalar: a Python loop
            p = libbtdf.make_params(n, s)
            T = libbtdf.transmittance(p, math.radians(deg))[0]
            for mode_name, kw, tol_T in (("analytic", {"mode": "analytic", "ior": str(n),
                                                       "smoothness": s}, 0.0),
                                         ("table", {"filename": tab(fname)},
                                          e_t * max(T, 0.01))):
                b = bsdf(**kw)
                for tm, scale in ((mi.TransportMode.Importance, 1.0),
                                  (mi.TransportMode.Radiance, 1.0 / (n * n))):
                    mean, err = mean_weight(b, tm, wi_of(deg), count, seed=7 + int(deg))
                    want = T * scale
                    # 4 standard errors of the mean, the quadrature's 1e-6 on T, and for
                    # the table its own reported e_T (relative to max(T, 0.01)).
                    tol = 4.0 * err + 1e-6 + tol_T * scale
                    check(abs(mean - want) <= tol,
                          "mean weight, %s, %s mode, n = %.4g, s = %g, ti = %g: %.6f +- "
                          "%.1g vs T %s= %.6f (|diff| %.2g, allowed %.2g)"
                          % (mode_name, "radiance" if tm == mi.TransportMode.Radiance
                             else "importance", n, s, deg, mean, err,
                             "/n^2 " if scale != 1.0 else "", want, abs(mean - want), tol))
                    if not JIT:
                        break  # scalar: importance mode only (Python loop per sample)


def mean_weight(b, mode, wi, count, seed):
    ctx = mi.BSDFContext(mode)
    if JIT:
        si = dr.zeros(mi.SurfaceInteraction3f, count)
        si.wi = mi.Vector3f(wi)
        rng = mi.PCG32(size=count, initstate=seed)
        _, w = b.sample(ctx, si, rng.next_float32(), mi.Point2f(rng.next_float32(),
                                                                   rng.next_float32()))
        x = mi.Float64(w[0])
        m = dr.mean(x)[0] if dr.width(dr.mean(x)) else dr.mean(x)
        m2 = dr.mean(x * x)[0]
        m = float(m)
    else:
        rng = random.Random(seed)
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(wi)
        acc = acc2 = 0.0
        for _ in range(count):
            _, w = b.sample(ctx, si, rng.random(), mi.Point2f(rng.random(), rng.random()))
            acc += float(w[0])
            acc2 += float(w[0]) ** 2
        m, m2 = acc / count, acc2 / count
    var = max(float(m2) - m * m, 0.0)
    return m, math.sqrt(var / count)


# ---------------------------------------------------------------------------------
# 3. a render: a rough face lit from behind (the paper's Fig. 11 set-up)
# ---------------------------------------------------------------------------------
def scene(bsdf_dict, res, spp):
    # Face of width 2 at z = 0, its normal (flipped) facing the light inside the
    # medium; the eye 0.8 face widths in front, the point light 0.8 widths behind.
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 70.0,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 1.6],
                                                              target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "face": {"type": "rectangle", "flip_normals": True, "bsdf": bsdf_dict},
        "light": {"type": "point", "position": [0.0, 0.0, -1.6],
                  "intensity": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
    }


def render(sc, spp, repeats):
    s = mi.load_dict(sc)
    times = []
    img = None
    for k in range(repeats):
        t = time.perf_counter()
        img = mi.render(s, spp=spp, seed=0)
        dr.eval(img)
        dr.sync_thread()
        times.append(time.perf_counter() - t)
    return img, times


def render_checks(res, spp, repeats):
    face = tab("face.csv")
    e_max = report_of("face.csv")["e_max"]["max"]
    n = libbtdf.Table(face).ior[0]
    s = libbtdf.Table(face).smoothness
    sc_t = scene({"type": "btdftab", "filename": face}, res, spp)
    sc_a = scene({"type": "btdftab", "filename": face, "mode": "analytic"}, res, spp)
    # roughdielectric: the normal faces the medium of index 1/n (the light's side)
    sc_r = scene({"type": "roughdielectric", "distribution": "beckmann", "alpha": 2.0 / s,
                  "int_ior": 1.0, "ext_ior": 1.0 / n, "sample_visible": True}, res, spp)
    img_t, tt = render(sc_t, spp, repeats)
    img_a, ta = render(sc_a, spp, repeats)
    img_r, tr = render(sc_r, spp, repeats)
    a = img_t.numpy()[..., 0].astype("float64")
    b = img_a.numpy()[..., 0].astype("float64")
    r = img_r.numpy()[..., 0].astype("float64")
    diff = abs(a - b).max() / b.max()
    flux = (r.sum() - b.sum()) / b.sum()
    med = lambda x: sorted(x)[len(x) // 2]  # noqa: E731
    print("# render %dx%d, %d spp, %s: seconds per render (first includes JIT compile), "
          "table %s, analytic %s, roughdielectric %s"
          % (res, res, spp, VARIANT, ["%.2f" % x for x in tt], ["%.2f" % x for x in ta],
             ["%.2f" % x for x in tr]))
    print("# render medians after the first: table %.2f s, analytic %.2f s, "
          "roughdielectric %.2f s; roughdielectric / analytic flux - 1 = %+.2e"
          % (med(tt[1:] or tt), med(ta[1:] or ta), med(tr[1:] or tr), flux))
    check(b.max() > 0 and all(map(math.isfinite, (a.sum(), b.sum()))),
          "render: finite and lit (peak %.4g)" % b.max())
    # Each pixel averages rho~ |cos| (table) and rho |cos| (analytic) over the same
    # paths (same seed, a point light: no noise between the two), so their difference
    # is the table's error |rho~ - rho| <= e_max max rho seen through the same weights.
    check(diff <= e_max, "render: table vs analytic max |diff| / peak = %.3g <= the "
          "table's reported e_max %.3g (n = %.4g, s = %g)" % (diff, e_max, n, s))
    # The documented XML scene (examples/mitsuba/face.xml) is the same scene.
    xml = mi.load_file(os.path.join(ROOT, "examples", "mitsuba", "face.xml"), filename=face,
                       spp="4", res="48")
    img_x = mi.render(xml, spp=4, seed=0)
    img_d = mi.render(mi.load_dict(scene({"type": "btdftab", "filename": face}, 48, 4)),
                      spp=4, seed=0)
    dx = float(dr.max(dr.abs(mi.TensorXf(img_x) - mi.TensorXf(img_d))).array[0])
    check(dx == 0.0, "examples/mitsuba/face.xml renders the same image as the scene dict "
          "(48x48, 4 spp): max |diff| %g" % dx)
    if RENDER_DIR:
        os.makedirs(RENDER_DIR, exist_ok=True)
        for name, img in (("table", img_t), ("analytic", img_a), ("roughdielectric", img_r)):
            mi.util.write_bitmap(os.path.join(RENDER_DIR, "face-%s.exr" % name), img,
                                 write_async=False)
            mi.util.write_bitmap(os.path.join(RENDER_DIR, "face-%s.png" % name), img,
                                 write_async=False)


def xml_check():
    b = mi.load_string('<bsdf version="3.0.0" type="btdftab"><string name="filename" '
                       'value="%s"/></bsdf>' % tab("f15.exr"))
    check("btdftab[mode=table" in str(b), "XML: <bsdf type=\"btdftab\"> loads: %s" % b)


def error_checks():
    for kw, want in (({}, "needs 'filename'"), ({"filename": tab("nonexistent.exr")},
                                                "nonexistent.exr"),
                     ({"mode": "fast", "filename": tab("f15.exr")}, "mode 'fast'"),
                     ({"filename": tab("f15.exr"), "filename_back": tab("f15.exr")},
                      "needs n =")):
        try:
            bsdf(**kw)
            msg = "(no error)"
        except Exception as e:  # Mitsuba wraps plugin errors
            msg = str(e)
        check(want in msg, "bad parameters %s: error names the problem: %s"
              % (kw, msg.strip().splitlines()[-1][:150]))


if __name__ == "__main__":
    t0 = time.time()
    print("# variant %s, mitsuba %s, drjit %s, libbtdf %s" % (
        VARIANT, mi.__version__, dr.__version__,
        libbtdf.library().btdf_version_string().decode()))
    if RENDER_ONLY:
        render_checks(256, 64, REPEATS)
        print("%d passed, %d failed" % (passed, failed))
        sys.exit(1 if failed else 0)
    eval_check("facet n = 1.5 s = 3", "f15.exr")
    eval_check("facet n = 1.5 s = 100", "f15s100.exr")
    eval_check("facet-reciprocal n = 0.6667 s = 6", "r066s6.exr")
    eval_check("grid n = 1.5 s = 3", "g15.exr")
    eval_check("facet 3 channels n = 1.51,1.52,1.53 s = 3", "f3.exr")
    eval_check("facet n = 1.5 + back table facet-reciprocal n = 0.6667", "f15.exr",
               back_name="f15back.exr")
    analytic_check()
    error_checks()
    xml_check()
    if JIT:
        chi2_checks()
        weight_checks(1000000)
        render_checks(256, 64, REPEATS)
    else:
        weight_checks(10000)
        render_checks(32, 4, 1)
    print("# %.1f s" % (time.time() - t0))
    print("%d passed, %d failed" % (passed, failed))
    sys.exit(1 if failed else 0)
