# SPDX-License-Identifier: MIT
"""Checks of the Mitsuba 3 plugin `btdftab` (python/btdftab_mitsuba), run by
tests/mitsuba.sh in a venv with mitsuba from PyPI:

    python tests/mitsuba_checks.py VARIANT TABLE_DIR [--render OUT_DIR] [--render-only]
        [--repeats N] [--part both|transmission]

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
PART = sys.argv[sys.argv.index("--part") + 1] if "--part" in sys.argv else "both"
mi.set_variant(VARIANT)
import btdftab_mitsuba  # noqa: E402  (registers the plugin)
import btdftab  # noqa: E402  (the binding the plugin uses: python/btdftab)

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


class lb:
    """The references, from libbtdf through the package btdftab: a material p (a list of
    indices, s, k0, model) and per-channel lists, as the checks compare them."""

    class Params:
        def __init__(self, ior, s, k0=0.7, model="xu-sun", paths=None):
            self.ior = list(ior) if isinstance(ior, (list, tuple)) else [ior]
            self.s, self.k0, self.model, self.paths = float(s), float(k0), model, paths
            btdftab.params_check(self.ior, s, k0, model)

    class Table:
        def __init__(self, path):
            self.t = btdftab.Table(path)
            self.ior, self.smoothness, self.model = self.t.ior, self.t.smoothness, self.t.model

        def eval(self, ti, to, phi):
            v = self.t.eval(ti, to, phi)
            return [float(x) for x in (v if self.t.channels == 3 else [v])]

    @staticmethod
    def make_params(ior, s, k0=0.7, model="xu-sun", paths=None):
        return lb.Params(ior, s, k0, model, paths)

    @staticmethod
    def _each(fn, p, *args):
        return [float(fn(n, p.s, *args, k0=p.k0, model=p.model, paths=p.paths))
                for n in p.ior]

    @staticmethod
    def rho(p, ti, to, phi):
        return lb._each(btdftab.rho, p, ti, to, phi)

    @staticmethod
    def rho_r(p, ti, tr, phi):
        return lb._each(btdftab.rho_r, p, ti, tr, phi)

    @staticmethod
    def transmittance(p, ti):
        return lb._each(btdftab.T, p, ti)

    @staticmethod
    def reflectance(p, ti):
        return lb._each(btdftab.R, p, ti)


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
    if a[0] == 0.0 and a[1] == 0.0:
        # a on the axis: phi is undefined; the plugin takes 0 there (plugin.py, _angles),
        # and so must the reference, as full's tallied series is not exactly even in phi
        # at ti = 0 (its m > 0 terms carry the tally's noise there)
        phi = 0.0
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
    front = lb.Table(tab(fname))
    back = lb.Table(tab(back_name)) if back_name else None
    kw = {"filename": tab(fname), "part": "transmission"}
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
        one = bsdf(filename=tab(fname), part="transmission")
        idx = [i for i in range(len(wis)) if wis[i][2] < 0]
        w1 = [wis[i] for i in idx]
        w2 = [wos[i] for i in idx]
        v2 = eval_many(b, mi.TransportMode.Importance, w1, w2)
        v1 = eval_many(one, mi.TransportMode.Importance, w1, w2)
        d = max(abs(x[0] - y[0]) for x, y in zip(v1, v2)) / max(x[0] for x in v1)
        check(0.0 < d < 0.01, "light from behind: back table vs front table by reciprocity "
              "differ by max %.3g of the peak (nonzero: the back table is used)" % d)
    return b


FULL_PATHS = 20000  # full's tally in these checks: a tenth of the default, for time


def analytic_check(pairs=10000, seed=2):
    """Mode analytic against btdf_eval (Eq. 25 of libbtdf; btdf_full_rho for full), both
    sides; part = both evaluates both lobes in one pass (model.rho_any), part =
    transmission the transmission alone; the models xu-sun, smith and full."""
    for n, s, part, model in ((1.5, 3.0, "transmission", "xu-sun"),
                              (1.0 / 1.5, 6.0, "transmission", "xu-sun"),
                              (1.5, 100.0, "transmission", "xu-sun"),
                              (1.5, 3.0, "both", "xu-sun"), (1.0 / 1.5, 6.0, "both", "xu-sun"),
                              (1.5, 100.0, "both", "xu-sun"),
                              (1.5, 1.0, "transmission", "smith"), (1.5, 3.0, "both", "smith"),
                              (1.0 / 1.5, 6.0, "both", "smith"),
                              (1.5, 1.0, "transmission", "full"), (1.5, 1.0, "both", "full")):
        extra = {"paths": FULL_PATHS} if model == "full" else {}
        paths = extra.get("paths")
        if model == "full" and not JIT:
            pairs = 1000  # full's series costs a few ms per Python-level evaluation
        b = bsdf(mode="analytic", ior=str(n), smoothness=s, part=part, model=model, **extra)
        p = lb.make_params(n, s, model=model, paths=paths)
        pb = lb.make_params(1.0 / n, s, model=model, paths=paths)
        rng = random.Random(seed)
        wis = [f32(rand_dir(rng, i % 2 == 0)) for i in range(pairs)]
        wos = [rand_dir(rng, w[2] < 0) for w in wis]
        lobe = sampled_dirs(bsdf(mode="analytic", ior=str(n), smoothness=s,
                                 part="transmission", model=model, **extra),
                            wis[pairs // 2:], rng)
        wos = [f32(w) for w in wos[:pairs // 2] + lobe]
        flip = lambda v: [v[0], v[1], -v[2]]  # noqa: E731
        for mode, mname in ((mi.TransportMode.Importance, "importance"),
                            (mi.TransportMode.Radiance, "radiance")):
            got = eval_many(b, mode, wis, wos)
            max_rel = 0.0
            bad = 0
            for a, c, g in zip(wis, wos, got):
                if a[2] * c[2] >= 0:
                    continue
                # light arrives along src: wi in importance mode, wo in radiance mode
                src, dst = (c, a) if mode == mi.TransportMode.Radiance else (a, c)
                ref = (lb.rho(p, *angles(src, dst)) if src[2] > 0
                       else lb.rho(pb, *angles(flip(src), flip(dst))))[0] * abs(c[2])
                d = abs(g[0] - ref)
                if ref >= FLT_MIN:
                    max_rel = max(max_rel, d / ref)
                # The model in double in both, then two float roundings; at s = 100
                # the lobe's exponent s^2 tan^2/4 amplifies double rounding of the
                # angles, measured < 1e-9; full's series (cancelling terms, python_pkg)
                # amplifies it to about 1e-13.
                if d > 2.0 * EPS32 * ref + FLT_MIN:
                    bad += 1
            check(bad == 0, "analytic mode = libbtdf, model %s, part = %s, %s mode, "
                  "n = %.4g, s = %g: max rel diff %.3g" % (model, part, mname, n, s,
                                                          max_rel))


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
    For s = 100 the lobe is about 0.4 degrees wide, below the sphere's cells at res = 101
    (50 x 101 over phi x cos theta: 7.2 degrees by 0.02), where the trapezoid rule
    cannot integrate the pdf over a cell."""

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
            # Samples outside the cone (the other lobe, when both are sampled) are not
            # counted, as the pdf is integrated over the cone alone: weight 0. Weight-0
            # samples add nothing to the histogram; put them inside the domain.
            l3 = dr.dot(wo, self.e3)
            xy = self.map_backward(wo)
            inside = (l3 > 0.0) & (dr.abs(xy.x) <= self.r) & (dr.abs(xy.y) <= self.r)
            w = dr.select(inside, w, 0.0)
            return dr.select(w > 0.0, wo, mi.Vector3f(self.e3)), w

        def pdf(w, *a):
            l3 = dr.dot(w, self.e3)
            return pf(w, *a) / (l3 * l3 * l3)  # (1+x^2+y^2)^-1.5 = l3^3 for unit w
        return sample, pdf


def pdf_adapter(d, wi):
    """Like mitsuba.chi2.BSDFAdapter, but a sample counts where the plugin gives it a
    pdf > 0, not where its weight is nonzero: at grazing exits the shadowing V(t)
    underflows float (t within 0.2 degrees of the horizon at s = 3), the weight is 0
    although the direction was drawn, and dropping those samples (2072 of 10^6 for
    light from behind at 70 degrees, one run) would make the histogram miss what the
    pdf holds."""
    plugin = mi.load_dict(d)
    ctx = mi.BSDFContext()

    def si_of(n):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(wi)
        return si

    def sample(u, *a):
        bs, _ = plugin.sample(ctx, si_of(dr.width(u)), u[0], mi.Vector2f(u[1], u[2]))
        return bs.wo, dr.select(bs.pdf > 0.0, mi.Float(1.0), mi.Float(0.0))

    def pdf(wo, *a):
        return plugin.pdf(ctx, si_of(dr.width(wo)), wo)
    return sample, pdf


def chi2_one(fname, wi, zoom=None, distort=False, part="transmission", extra=None):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain
    d = {"type": "btdftab", "part": part}
    if fname:
        d["filename"] = tab(fname)
    d.update(extra or {})
    if part == "transmission":  # as measured before both lobes existed
        sf, pf = BSDFAdapter("btdftab", d, wi=wi)
    else:
        sf, pf = pdf_adapter(d, wi)
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
                     else "50 x 101 cells (phi, cos theta) over the sphere",
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
            p = lb.make_params(n, s)
            T = lb.transmittance(p, math.radians(deg))[0]
            for mode_name, kw, tol_T in (("analytic", {"mode": "analytic", "ior": str(n),
                                                       "smoothness": s}, 0.0),
                                         ("table", {"filename": tab(fname)},
                                          e_t * max(T, 0.01))):
                kw = dict(kw, part="transmission")
                b = bsdf(**kw)
                for tm, scale in ((mi.TransportMode.Importance, 1.0),
                                  (mi.TransportMode.Radiance, 1.0 / (n * n))):
                    mean, err = mean_weights(b, tm, wi_of(deg), count, seed=7 + int(deg))[0]
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


# ---------------------------------------------------------------------------------
# 2b. the reflection of the same facets, and both lobes sampled together (part = both,
#     the default): eval against btdf_eval_r, the mean weight against R + T, chi-square
# ---------------------------------------------------------------------------------
def inv_params(ior, s, k0, model="xu-sun", paths=None):
    return (lb.make_params(ior, s, k0, model, paths),
            lb.make_params([1.0 / n for n in ior], s, k0, model, paths))


def eval_r_check(label, kw, pairs=10000, seed=3):
    """eval at same-side pairs = btdf_eval_r (n in front, 1/n behind) times |cos wo|."""
    if kw.get("model") == "full" and not JIT:
        pairs = 1000  # full's series costs a few ms per Python-level evaluation
    b = bsdf(**kw)  # part = both: the default
    lobe_b = bsdf(**dict(kw, part="reflection"))
    if "filename" in kw:
        t = lb.Table(kw["filename"])
        ior, s, k0, model = t.ior, t.smoothness, t.t.k0, t.model
    else:
        ior = [float(x) for x in kw["ior"].split(",")]
        s, k0, model = kw["smoothness"], 0.7, kw.get("model", "xu-sun")
    pf, pb = inv_params(ior, s, k0, model, kw.get("paths"))
    rng = random.Random(seed)
    wis = [f32(rand_dir(rng, i % 2 == 0)) for i in range(pairs)]  # half from behind
    wos = [rand_dir(rng, w[2] > 0) for w in wis]  # the same side
    lobe = sampled_dirs(lobe_b, wis[pairs // 2:], rng)  # the second half: in the lobe
    wos = [f32(w) for w in wos[:pairs // 2] + lobe]
    keep = [i for i in range(pairs) if wis[i][2] * wos[i][2] > 0]
    wis = [wis[i] for i in keep]
    wos = [wos[i] for i in keep]
    flip = lambda v: [v[0], v[1], -v[2]]  # noqa: E731
    for mode, mname in ((mi.TransportMode.Importance, "importance"),
                        (mi.TransportMode.Radiance, "radiance")):
        # the light arrives along wi (importance) or wo (radiance): rho_r of xu-sun and
        # smith is reciprocal, full's multiply scattered part only in the mean
        refs = []
        for a, c in zip(wis, wos):
            src, dst = (c, a) if mode == mi.TransportMode.Radiance else (a, c)
            r = (lb.rho_r(pf, *angles(src, dst)) if src[2] > 0
                 else lb.rho_r(pb, *angles(flip(src), flip(dst))))
            refs.append([x * abs(c[2]) for x in r])
        got = eval_many(b, mode, wis, wos)
        max_rel, peak = [0.0, 0.0], [0.0, 0.0]
        bad = 0
        for a, g, ref in zip(wis, got, refs):
            side = 0 if a[2] > 0 else 1
            for ch in range(3):
                r = ref[min(ch, len(ref) - 1)]
                d = abs(g[ch] - r)
                peak[side] = max(peak[side], r)
                if r >= FLT_MIN:
                    max_rel[side] = max(max_rel[side], d / r)
                # as for the transmission: rho_r in double, then two float roundings
                if d > 2.0 * EPS32 * r + FLT_MIN:
                    bad += 1
        check(bad == 0 and min(peak) > 0.0,
              "reflection eval = btdf_eval_r |cos wo|, %s, %s mode, %d same-side pairs; "
              "light in front / behind: max rel diff %.3g / %.3g (values >= FLT_MIN), "
              "peak %.4g / %.4g; %d beyond 2 eps32 |ref| + FLT_MIN"
              % (label, mname, len(wis), max_rel[0], max_rel[1], peak[0], peak[1], bad))


def component_checks():
    """Mitsuba's context selects one lobe: component 0 is the reflection, 1 the
    transmission; the type mask likewise."""
    b = bsdf(mode="analytic", ior="1.5", smoothness=3.0)
    t = math.radians(40.0)
    wi = [math.sin(t), 0.0, math.cos(t)]
    wr = [-0.5, 0.1, math.sqrt(1.0 - 0.26)]
    wt = [-0.3, 0.1, -math.sqrt(1.0 - 0.1)]
    res = {}
    for name, comp, mask in (("all", None, None), ("component 0", 0, None),
                             ("component 1", 1, None),
                             ("GlossyReflection", None, mi.BSDFFlags.GlossyReflection),
                             ("GlossyTransmission", None, mi.BSDFFlags.GlossyTransmission)):
        ctx = mi.BSDFContext()
        if comp is not None:
            ctx.component = comp
        if mask is not None:
            ctx.type_mask = mask
        vals = []
        for wo in (wr, wt):
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = mi.Vector3f(wi)
            v = b.eval(ctx, si, mi.Vector3f(wo))
            p = b.pdf(ctx, si, mi.Vector3f(wo))
            vals.append((float(dr.ravel(v)[0]) if JIT else float(v[0]),
                         float(dr.ravel(p)[0]) if JIT else float(p)))
        res[name] = vals
    ok = (all(x > 0 for x in res["all"][0] + res["all"][1])
          and res["component 0"][0][0] == res["all"][0][0]
          and res["component 0"][1] == (0.0, 0.0)
          and res["component 1"][1][0] == res["all"][1][0]
          and res["component 1"][0] == (0.0, 0.0)
          and res["GlossyReflection"][0] == res["component 0"][0]
          and res["GlossyTransmission"][1] == res["component 1"][1]
          and res["component 0"][0][1] > res["all"][0][1]
          and res["component 1"][1][1] > res["all"][1][1])
    check(ok and b.component_count() == 2 and
          mi.has_flag(b.flags(), mi.BSDFFlags.GlossyReflection) and
          mi.has_flag(b.flags(), mi.BSDFFlags.GlossyTransmission),
          "components: reflection (0) and transmission (1) selectable by index and type "
          "mask; (eval, pdf) all / reflection pair %s, transmission pair %s; component 0: "
          "%s; component 1: %s" % (res["all"][0], res["all"][1], res["component 0"],
                                   res["component 1"]))
    bt = bsdf(mode="analytic", ior="1.5", smoothness=3.0, part="transmission")
    check(bt.component_count() == 1 and not mi.has_flag(bt.flags(),
                                                        mi.BSDFFlags.GlossyReflection),
          "part = transmission: one component, GlossyTransmission (today's surface)")


def mean_weights(b, mode, wi, count, seed):
    """Per channel (mean, standard error) of the sampled weight."""
    ctx = mi.BSDFContext(mode)
    if JIT:
        si = dr.zeros(mi.SurfaceInteraction3f, count)
        si.wi = mi.Vector3f(wi)
        rng = mi.PCG32(size=count, initstate=seed)
        _, w = b.sample(ctx, si, rng.next_float32(), mi.Point2f(rng.next_float32(),
                                                                   rng.next_float32()))
        out = []
        for c in range(3):
            x = mi.Float64(w[c])
            m = float(dr.mean(x)[0])
            m2 = float(dr.mean(x * x)[0])
            out.append((m, math.sqrt(max(m2 - m * m, 0.0) / count)))
        return out
    rng = random.Random(seed)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(wi)
    acc, acc2 = [0.0] * 3, [0.0] * 3
    for _ in range(count):
        _, w = b.sample(ctx, si, rng.random(), mi.Point2f(rng.random(), rng.random()))
        for c in range(3):
            acc[c] += float(w[c])
            acc2[c] += float(w[c]) ** 2
    out = []
    for c in range(3):
        m = acc[c] / count
        out.append((m, math.sqrt(max(acc2[c] / count - m * m, 0.0) / count)))
    return out


# (label, plugin parameters, n, s, angles from the front, angles from behind); behind
# means index 1/n, total internal reflection past 41.8 degrees for n = 1.5.
ALBEDO_CASES = [
    ("analytic", {"mode": "analytic", "ior": "1.5", "smoothness": 3.0}, [1.5], 3.0,
     [0.0, 30.0, 60.0, 80.0], [0.0, 30.0, 45.0, 60.0, 80.0]),
    ("analytic", {"mode": "analytic", "ior": "1.5", "smoothness": 100.0}, [1.5], 100.0,
     [0.0, 60.0], [30.0, 60.0]),
    ("analytic", {"mode": "analytic", "ior": "0.6666667", "smoothness": 6.0},
     [0.6666667], 6.0, [20.0, 60.0], [20.0, 60.0]),
    ("analytic, 3 channels", {"mode": "analytic", "ior": "1.51,1.52,1.53",
                              "smoothness": 3.0}, [1.51, 1.52, 1.53], 3.0, [45.0], [30.0]),
    ("table + back table", {"filename": "f15.exr", "filename_back": "f15back.exr"}, [1.5],
     3.0, [30.0, 60.0], [30.0, 60.0]),
]


def albedo_checks(count):
    """The mean sampled weight of both lobes against R(ti) + T(ti) (importance mode) and
    R + T/n^2 (radiance mode), light in front (index n) and behind (1/n)."""
    for label, kw, ior, s, front, behind in ALBEDO_CASES:
        kw = dict(kw)
        e_t = [0.0, 0.0]
        if "filename" in kw:
            e_t = [report_of(kw["filename"])["e_t"]["max"],
                   report_of(kw["filename_back"])["e_t"]["max"]]
            kw["filename"] = tab(kw["filename"])
            kw["filename_back"] = tab(kw["filename_back"])
        b = bsdf(**kw)
        pf, pb = inv_params(ior, s, 0.7)
        for side, p, degs in ((1.0, pf, front), (-1.0, pb, behind)):
            ns = ior if side > 0 else [1.0 / n for n in ior]
            etab = e_t[0] if side > 0 else e_t[1]
            for deg in (degs if JIT else degs[:1]):
                R = lb.reflectance(p, math.radians(deg))
                T = lb.transmittance(p, math.radians(deg))
                for tm in ((mi.TransportMode.Importance, mi.TransportMode.Radiance)
                           if JIT else (mi.TransportMode.Importance,)):
                    rad = tm == mi.TransportMode.Radiance
                    res = mean_weights(b, tm, wi_of(deg, side), count, seed=11 + int(deg))
                    worst = 0.0
                    ok = True
                    txt = []
                    for c in range(len(ior)):
                        sc = 1.0 / (ns[c] * ns[c]) if rad else 1.0
                        want = R[c] + T[c] * sc
                        mean, err = res[c]
                        # 4 standard errors, the quadratures' errors (T 1e-6, R 1e-8),
                        # and for a table its reported e_T on the transmitted part
                        tol = 4.0 * err + 1.01e-6 + etab * max(T[c], 0.01) * sc
                        ok &= abs(mean - want) <= tol
                        worst = max(worst, abs(mean - want) / tol)
                        txt.append("%.6f +- %.1g vs R + T%s = %.6f + %.6f = %.6f "
                                   "(allowed %.2g)" % (mean, err, "/n^2" if rad else "",
                                                       R[c], T[c] * sc, want, tol))
                    check(ok, "albedo, %s, n = %s, s = %g, light %s, ti = %g, %s mode: %s"
                          % (label, "/".join("%.4g" % n for n in ns), s,
                             "in front" if side > 0 else "behind", deg,
                             "radiance" if rad else "importance", "; ".join(txt)))
    # The reflection alone (part = reflection) against R: the lobe without the choice.
    b = bsdf(mode="analytic", ior="1.5", smoothness=3.0, part="reflection")
    pf, pb = inv_params([1.5], 3.0, 0.7)
    for side, p, deg in ((1.0, pf, 60.0), (-1.0, pb, 30.0), (-1.0, pb, 60.0)):
        R = lb.reflectance(p, math.radians(deg))[0]
        mean, err = mean_weights(b, mi.TransportMode.Importance, wi_of(deg, side),
                                 count, seed=5)[0]
        tol = 4.0 * err + 1e-8
        check(abs(mean - R) <= tol, "part = reflection, n = %.4g, s = 3, ti = %g: mean "
              "weight %.6f +- %.1g vs R = %.6f (allowed %.2g)"
              % (1.5 if side > 0 else 1 / 1.5, deg, mean, err, R, tol))


def chi2_both_checks():
    """Chi-square tests of both lobes sampled together (part = both): the pdf of the
    lobe choice (the facet's Fresnel) must match the sampler on the whole sphere."""
    tests = [("f15.exr", None, 1.0, d, None) for d in (0.0, 30.0, 60.0, 80.0)]
    tests += [("f15.exr", None, -1.0, d, None) for d in (20.0, 45.0, 70.0)]
    tests += [("r066s6.exr", None, 1.0, d, None) for d in (30.0, 60.0)]
    tests += [("f3.exr", None, 1.0, 45.0, None)]
    # s = 100: 101 x 101 cells within 0.15 rad of the mirror direction (the reflection
    # lobe; the transmitted samples fall outside and are not counted)
    for d in (0.0, 60.0):
        t = math.radians(d)
        tests.append((None, {"mode": "analytic", "ior": "1.5", "smoothness": 100.0}, 1.0, d,
                      ZoomDomain([-math.sin(t), 0.0, math.cos(t)], 0.15)))
    ntests = len(tests) + 1
    for fname, extra, side, deg, zoom in tests:
        chi = chi2_one(fname, wi_of(deg, side), zoom, part="both", extra=extra)
        ok = chi.run(0.01, test_count=ntests, quiet=True)
        check(ok, "chi2, both lobes: %s, light %s, ti = %g deg, p-value %.3g%s"
              % (fname or "analytic n = 1.5, s = 100 (0.15 rad around the mirror "
                 "direction)", "in front" if side > 0 else "behind", deg, chi.p_value,
                 "" if ok else ": " + chi.messages.strip()))
    # Negative control: a reflection pdf 20% too high must be rejected.
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain
    sf, pf = pdf_adapter({"type": "btdftab", "filename": tab("f15.exr")}, wi_of(60.0))
    chi = ChiSquareTest(domain=SphericalDomain(), sample_func=sf,
                        pdf_func=lambda w, *a: pf(w, *a) * dr.select(w.z > 0.0, 1.2, 1.0),
                        sample_dim=3, sample_count=1000000, res=101, ires=8)
    ok = not chi.run(0.01, test_count=ntests, quiet=True)
    check(ok, "chi2 rejects a reflection pdf scaled by 1.2 (n = 1.5, s = 3, ti = 60): "
          "p-value %.3g" % chi.p_value)


def finite_checks(count):
    """No NaN or inf, nor a negative value, from eval, pdf and sample, over random
    directions and the edge cases: grazing (z = 0, +-1e-7), the axis, wo = wi, wo = -wi."""
    rng = random.Random(9)
    wis, wos = [], []
    edge = [[1.0, 0.0, 0.0], [1.0, 0.0, 1e-7], [1.0, 0.0, -1e-7], [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0], [0.6, 0.0, 0.8], [-0.6, 0.0, -0.8], [0.0, 1.0, 0.0]]
    for a in edge:
        for c in edge:
            wis.append(a)
            wos.append(c)
            wis.append(a)
            wos.append([-x for x in a])
    while len(wis) < count:
        wis.append(unit([rng.gauss(0, 1) for _ in range(3)]))
        wos.append(unit([rng.gauss(0, 1) for _ in range(3)]))
    u = [(rng.random(), rng.random(), rng.random()) for _ in wis]
    u[:8] = [(0.0, 0.0, 0.0), (0.999999, 0.999999, 0.999999), (0.5, 0.0, 0.5),
             (0.5, 0.999999, 0.0), (0.0, 0.5, 0.5), (0.3, 0.5, 1e-7), (0.9, 1e-7, 0.5),
             (0.1, 0.5, 0.999999)]
    for label, kw in (("analytic 1.5, s = 3", {"mode": "analytic", "ior": "1.5",
                                               "smoothness": 3.0}),
                      ("analytic 1.5, s = 100", {"mode": "analytic", "ior": "1.5",
                                                 "smoothness": 100.0}),
                      ("analytic 1.001, s = 1000", {"mode": "analytic", "ior": "1.001",
                                                    "smoothness": 1000.0}),
                      ("analytic 0.5, s = 0.5", {"mode": "analytic", "ior": "0.5",
                                                 "smoothness": 0.5}),
                      ("table f15.exr", {"filename": tab("f15.exr")}),
                      ("table f3.exr", {"filename": tab("f3.exr")})):
        b = bsdf(**kw)
        bad = total = 0
        for tm in (mi.TransportMode.Importance, mi.TransportMode.Radiance):
            ctx = mi.BSDFContext(tm)
            if JIT:
                si = dr.zeros(mi.SurfaceInteraction3f, len(wis))
                si.wi = mi.Vector3f(*[[w[i] for w in wis] for i in range(3)])
                wo = mi.Vector3f(*[[w[i] for w in wos] for i in range(3)])
                v = b.eval(ctx, si, wo)
                p = b.pdf(ctx, si, wo)
                bs, w = b.sample(ctx, si, mi.Float([x[0] for x in u]),
                                 mi.Point2f([x[1] for x in u], [x[2] for x in u]))
                arrs = [v[0], v[1], v[2], p, bs.pdf, w[0], w[1], w[2]]
                vals = [x for a in arrs for x in a.numpy().tolist()]
            else:
                vals = []
                for a, c, x in list(zip(wis, wos, u))[:500]:
                    si = dr.zeros(mi.SurfaceInteraction3f)
                    si.wi = mi.Vector3f(a)
                    v = b.eval(ctx, si, mi.Vector3f(c))
                    bs, w = b.sample(ctx, si, x[0], mi.Point2f(x[1], x[2]))
                    vals += [float(v[0]), float(b.pdf(ctx, si, mi.Vector3f(c))),
                             float(bs.pdf), float(w[0])]
            bad += sum(1 for x in vals if not (math.isfinite(x) and x >= 0.0))
            total += len(vals)
        check(bad == 0, "finite and >= 0: eval, pdf, sample of %s (part = both), both "
              "transport modes, %d values; %d not" % (label, total, bad))


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
    n = lb.Table(face).ior[0]
    s = lb.Table(face).smoothness
    sc_t = scene({"type": "btdftab", "filename": face, "part": PART}, res, spp)
    sc_a = scene({"type": "btdftab", "filename": face, "mode": "analytic", "part": PART},
                 res, spp)
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


def furnace_checks(res, spp):
    """A white furnace through Mitsuba's path tracer: an orthographic camera sees a large
    btdftab plane at incidence ti, radiance 1 in every direction, one bounce
    (max_depth = 2; emitter sampling and BSDF sampling weighted by MIS, so eval and pdf
    both enter). Each pixel estimates R(ti) + T(ti)/n^2 (radiance mode: camera paths),
    with n the index ratio seen from the camera's side; flipping the plane's normal puts
    the camera behind (1/n, total internal reflection past 41.8 degrees)."""
    n, s = 1.5, 3.0
    for side, deg in ((1.0, 0.0), (1.0, 60.0), (-1.0, 30.0), (-1.0, 60.0)):
        t = math.radians(deg)
        sc = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
            "sensor": {"type": "orthographic",
                       "to_world": mi.ScalarTransform4f().look_at(
                           origin=[5.0 * math.sin(t), 0.0, 5.0 * math.cos(t)],
                           target=[0, 0, 0], up=[0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": res, "height": res,
                                "rfilter": {"type": "box"}},
                       "sampler": {"type": "independent", "sample_count": spp}},
            "plane": {"type": "rectangle", "flip_normals": side < 0,
                      "to_world": mi.ScalarTransform4f().scale([20.0, 20.0, 1.0]),
                      "bsdf": {"type": "btdftab", "mode": "analytic", "ior": n,
                               "smoothness": s}},
            "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        }
        img = mi.render(mi.load_dict(sc), spp=spp, seed=1)
        a = img.numpy()[..., 0].astype("float64").ravel()
        mean = float(a.mean())
        err = float(a.std()) / math.sqrt(len(a))  # pixels are independent estimates
        ns = n if side > 0 else 1.0 / n
        p = lb.make_params(ns, s)
        R = lb.reflectance(p, t)[0]
        T = lb.transmittance(p, t)[0]
        want = R + T / (ns * ns)
        tol = 4.0 * err + 1.01e-6  # 4 standard errors, the quadratures' errors
        check(abs(mean - want) <= tol and all(map(math.isfinite, a)),
              "white furnace render (path, max_depth 2, %dx%d, %d spp), n = %.4g, s = %g, "
              "camera %s at %g deg: mean pixel %.6f +- %.1g vs R + T/n^2 = %.6f + %.6f = "
              "%.6f (|diff| %.2g, allowed %.2g)"
              % (res, res, spp, ns, s, "in front" if side > 0 else "behind", deg, mean, err,
                 R, T / (ns * ns), want, abs(mean - want), tol))


def series_energy(full, deg, side, nmu=256, nphi=512):
    """The hemispherical integral of full's multiply scattered part as libbtdf evaluates
    it, c max(0, series) (btdf/btdf.h, btdf_full_get_series), at ti = deg: a midpoint rule
    on nmu x nphi cells in (mu, phi), with the weight mu of the cosine. At ti = 0 the
    incident direction has no azimuth and the plugin, as the checks' reference, takes
    phi = 0 for every outgoing direction (plugin.py, _angles): so does this integral
    there. (The tally's m > 0 terms at ti = 0 are noise, not 0, so the choice shows:
    3.5e-3 of R + T at n = 1.5, s = 1, 20,000 walks: 1.007978 against 1.004508.)"""
    import numpy as np
    sr = full.series()
    nodes, poly, coef = sr["node_deg"], sr["poly"], sr["coef"]
    k = 0
    while k < len(nodes) - 2 and deg > nodes[k + 1]:
        k += 1
    w = min(1.0, max(0.0, (deg - nodes[k]) / (nodes[k + 1] - nodes[k])))
    mu = (np.arange(nmu) + 0.5) / nmu
    ph = (np.arange(nphi) + 0.5) / nphi * 2.0 * math.pi
    st = np.sqrt(1.0 - mu * mu)
    v = np.zeros((nmu, nphi))
    for j in range(poly.shape[1]):
        for m in range(poly.shape[0]):
            cf = (1 - w) * coef[k, side, j, m] + w * coef[k + 1, side, j, m]
            cph = np.ones_like(ph) if deg == 0.0 else np.cos(m * ph)
            v += (cf * np.polyval(poly[m, j][::-1], mu) * st ** m)[:, None] * cph[None, :]
    x = w * btdftab.SERIES_SUB  # the clip's energy factor (btdf/btdf.h)
    q = min(int(x), btdftab.SERIES_SUB - 1)
    fac = (1 - (x - q)) * sr["clip"][k, q, side] + (x - q) * sr["clip"][k, q + 1, side]
    v = fac * np.maximum(v, 0.0)
    return float((v * mu[:, None]).sum() * (1.0 / nmu) * (2.0 * math.pi / nphi))


def full_albedo_checks(count):
    """full (mode analytic): the mean sampled weight of both lobes against its R + T,
    light in front (n) and behind (1/n), importance mode (where the weight integrates
    rho(wi -> wo), exactly what R + T is). The sampling mixes cosine directions into the
    facets' (plugin.py), so this checks that mixture's pdf against its draws. R + T:
    smith's quadratures (1e-6) plus the integral of the clipped series (series_energy;
    its midpoint rule on 256 x 512 cells of a function with a kink where the clip acts:
    1e-4, measured against 512 x 1024 cells below 2e-5)."""
    n, s = 1.5, 1.0
    b = bsdf(mode="analytic", ior=str(n), smoothness=s, model="full", paths=FULL_PATHS)
    for side, deg in ((1.0, 0.0), (1.0, 60.0), (-1.0, 30.0), (-1.0, 60.0)):
        ns = n if side > 0 else 1.0 / n
        f = btdftab.Full(ns, s, FULL_PATHS)
        t = math.radians(deg)
        want = (btdftab.T(ns, s, t, model="smith") + btdftab.R(ns, s, t, model="smith") +
                series_energy(f, deg, 0) + series_energy(f, deg, 1))
        mean, err = mean_weights(b, mi.TransportMode.Importance, wi_of(deg, side), count,
                                 seed=21 + int(deg))[0]
        tol = 4.0 * err + 1e-4 + 1.01e-6
        check(abs(mean - want) <= tol, "full, n = %.4g, s = %g, ti = %g: mean sampled "
              "weight %.6f +- %.1g vs R + T = %.6f (allowed %.2g)"
              % (ns, s, deg, mean, err, want, tol))


def slab_furnace(model, deg, res, spp, s=1.0, n=1.5, table=None):
    """A white furnace of a closed rough glass slab (a box 20 x 20 x 1, every face the
    btdftab interface of index n, normals out) in radiance 1, seen by an orthographic
    camera at deg from its normal: paths to any depth (Russian roulette past depth 8, so
    the light inside the slab is followed until it leaves). A surface that loses no
    light returns 1 in every pixel. (mean, standard error of the mean over pixels).
    With a table, the slab's BSDF is that file (mode table; its model is the file's)."""
    t = math.radians(deg)
    kw = {"paths": FULL_PATHS} if model == "full" else {}
    bsdf_d = dict({"type": "btdftab", "mode": "analytic", "ior": str(n), "smoothness": s,
                   "model": model}, **kw)
    if table:
        bsdf_d = {"type": "btdftab", "filename": table}
    sc = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1, "rr_depth": 8,
                       "hide_emitters": True},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(
                       origin=[10.0 * math.sin(t), 0.0, 10.0 * math.cos(t)],
                       target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "slab": {"type": "cube",
                 "to_world": mi.ScalarTransform4f().scale([10.0, 10.0, 0.5]),
                 "bsdf": bsdf_d},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    }
    img = mi.render(mi.load_dict(sc), spp=spp, seed=3)
    a = img.numpy()[..., 0].astype("float64").ravel()
    return float(a.mean()), float(a.std()) / math.sqrt(len(a)), bool(all(map(math.isfinite, a)))


def slab_furnace_checks(res, spp):
    """full returns 1 within its tolerance, 1e-2 of the flux (docs/model.md section 12:
    R + T = 1 within it at every angle), plus 4 standard errors of the render; xu-sun and
    smith are measured (the light they lose)."""
    for deg in (0.0, 60.0):
        got = {}
        for model in ("xu-sun", "smith", "full"):
            mean, err, fin = slab_furnace(model, deg, res, spp)
            got[model] = mean
            print("# slab furnace, n = 1.5, s = 1, %g deg, %dx%d, %d spp: model %s %.4f "
                  "+- %.1g (loses %.1f%%)" % (deg, res, res, spp, model, mean, err,
                                               100.0 * (1.0 - mean)))
            if model == "full":
                tol = 1e-2 + 4.0 * err
                check(fin and abs(mean - 1.0) <= tol,
                      "white furnace, rough glass slab (n = 1.5, s = 1), model full, camera "
                      "at %g deg: %.4f +- %.1g, |1 - mean| %.2g <= %.2g"
                      % (deg, mean, err, abs(1.0 - mean), tol))
        check(got["xu-sun"] < got["smith"] < got["full"],
              "slab furnace at %g deg: xu-sun %.4f < smith %.4f < full %.4f (each model "
              "keeps more of the light)" % (deg, got["xu-sun"], got["smith"], got["full"]))
        # The table of full (tabulate --model full -s 1 at 1e-2): the model's tolerance
        # plus the table's own e_T (its flux error per crossing, from its report) times
        # 2, a path's crossings of a face at normal incidence (in and out; the light
        # trapped inside makes more, each weighted less)
        mean, err, fin = slab_furnace("full", deg, res, spp, table=tab("ffu1.exr"))
        e_t = report_of("ffu1.exr")["e_t"]["max"]
        tol = 1e-2 + 2.0 * e_t + 4.0 * err
        check(fin and abs(mean - 1.0) <= tol,
              "white furnace, rough glass slab, the full table ffu1.exr (n = 1.5, s = 1, "
              "1e-2), camera at %g deg: %.4f +- %.1g, |1 - mean| %.2g <= %.2g"
              % (deg, mean, err, abs(1.0 - mean), tol))


def xml_check():
    b = mi.load_string('<bsdf version="3.0.0" type="btdftab"><string name="filename" '
                       'value="%s"/></bsdf>' % tab("f15.exr"))
    check("btdftab[mode=table" in str(b), "XML: <bsdf type=\"btdftab\"> loads: %s" % b)


def error_checks():
    for kw, want in (({}, "needs 'filename'"), ({"filename": tab("nonexistent.exr")},
                                                "nonexistent.exr"),
                     ({"mode": "fast", "filename": tab("f15.exr")}, "mode 'fast'"),
                     ({"part": "glass", "filename": tab("f15.exr")}, "part 'glass'"),
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
        btdftab.version()))
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
    eval_check("facet smith n = 1.5 s = 3", "fsm15.exr")
    eval_check("facet-reciprocal smith n = 0.6667 s = 6", "rsm066s6.exr")
    eval_check("facet full n = 1.5 s = 1 (the file's tally added)", "ffu1.exr")
    analytic_check()
    eval_r_check("analytic n = 1.5, s = 3", {"mode": "analytic", "ior": "1.5",
                                              "smoothness": 3.0})
    eval_r_check("analytic n = 0.6667, s = 6", {"mode": "analytic", "ior": "0.6666667",
                                                 "smoothness": 6.0})
    eval_r_check("analytic n = 1.5, s = 100", {"mode": "analytic", "ior": "1.5",
                                                "smoothness": 100.0})
    eval_r_check("analytic n = 1.01, s = 3 (Fr about 2.5e-5)",
                 {"mode": "analytic", "ior": "1.01", "smoothness": 3.0})
    eval_r_check("table f15.exr (reflection from the model)", {"filename": tab("f15.exr")})
    eval_r_check("table fsm15.exr (smith's reflection)", {"filename": tab("fsm15.exr")})
    eval_r_check("table ffu1.exr (full's reflection: the file's tally in front, one of "
                 "1/n made at load behind)", {"filename": tab("ffu1.exr")},
                 pairs=10000 if JIT else 1000)
    eval_r_check("analytic smith n = 1.5, s = 1", {"mode": "analytic", "ior": "1.5",
                                                   "smoothness": 1.0, "model": "smith"})
    eval_r_check("analytic full n = 1.5, s = 1", {"mode": "analytic", "ior": "1.5",
                                                  "smoothness": 1.0, "model": "full",
                                                  "paths": FULL_PATHS})
    eval_r_check("table f3.exr, 3 channels", {"filename": tab("f3.exr")})
    component_checks()
    finite_checks(20000 if JIT else 500)
    error_checks()
    xml_check()
    if JIT:
        chi2_checks()
        chi2_both_checks()
        weight_checks(1000000)
        albedo_checks(1000000)
        furnace_checks(64, 64)
        full_albedo_checks(1000000)
        slab_furnace_checks(64, 256)
        render_checks(256, 64, REPEATS)
    else:
        weight_checks(10000)
        albedo_checks(10000)
        full_albedo_checks(10000)
        render_checks(32, 4, 1)
    print("# %.1f s" % (time.time() - t0))
    print("%d passed, %d failed" % (passed, failed))
    sys.exit(1 if failed else 0)
