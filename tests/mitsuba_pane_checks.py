# SPDX-License-Identifier: MIT
"""Checks of the Mitsuba 3 thin-sheet BSDF `btdftab_pane` (python/btdftab_mitsuba/pane.py),
run by tests/mitsuba.sh in a venv with mitsuba from PyPI:

    python tests/mitsuba_pane_checks.py VARIANT

eval against libbtdf's btdf_pane_eval (both transport modes, both sides, one and three
channels), chi-square tests of the sampler (JIT variants), the mean sampled weight
against the integral of the BSDF computed here on a fine grid, a white furnace through
Mitsuba's path tracer, an XML scene, bad parameters. Prints one "ok" / "not ok" line
per check and "N passed, N failed" last.
"""
import math
import os
import random
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

VARIANT = sys.argv[1]
mi.set_variant(VARIANT)
import btdftab  # noqa: E402
import btdftab_mitsuba  # noqa: E402,F401  (registers btdftab and btdftab_pane)

JIT = dr.is_jit_v(mi.Float)
EPS32 = 2.0 ** -23
passed = failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
    else:
        failed += 1
    print("%s %d - %s" % ("ok" if ok else "not ok", passed + failed, what))
    sys.stdout.flush()


# The panes: a flat back with a little absorption (the delta of the back's mirror); a
# rough back, three channels, a smaller quadrature (it builds in a second).
A = {"ior": 1.5, "smoothness": 3.0, "back": "smooth", "absorption": 0.01}
B = {"ior": "1.51,1.52,1.53", "smoothness": 2.0, "back": 5.0, "thickness": 2.0,
     "nodes": 40, "modes": 48}
_loaded = {}


def plugin(case):
    key = repr(sorted(case.items()))
    if key not in _loaded:
        _loaded[key] = mi.load_dict(dict(type="btdftab_pane", **case))
    return _loaded[key]


def f32(x):
    return np.asarray(x, dtype=np.float32).astype(np.float64)


def ref_f(pane, src, dst):
    """libbtdf's f(light along src -> dst) per channel, in double, for unit directions."""
    front = src[2] > 0.0
    sg = 1.0 if front else -1.0
    a = src * [1.0, 1.0, sg]
    b = dst * [1.0, 1.0, sg]
    sa = math.hypot(a[0], a[1])
    ax, ay = (a[0] / sa, a[1] / sa) if sa > 0 else (1.0, 0.0)  # the plugin's reference
    ph = abs(math.atan2(ax * b[1] - ay * b[0], ax * b[0] + ay * b[1]))
    through = b[2] < 0.0
    ti = math.acos(min(a[2], 1.0))
    to = math.acos(max(min(b[2], 1.0), -1.0))
    return np.atleast_1d(pane.eval(ti, to, ph, light="front" if front else "back",
                                   part="transmission" if through else "reflection"))


def eval_values(b, mode, wis, wos):
    ctx = mi.BSDFContext(mode)
    if JIT:
        si = dr.zeros(mi.SurfaceInteraction3f, len(wis))
        si.wi = mi.Vector3f(wis.T)
        v = b.eval(ctx, si, mi.Vector3f(wos.T))
        return np.array(v).T.astype(np.float64)
    out = []
    for a, c in zip(wis, wos):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*a)
        out.append([float(x) for x in b.eval(ctx, si, mi.Vector3f(*c))])
    return np.array(out)


def eval_checks(label, case, count, seed):
    """eval against btdf_pane_eval: the plugin sums the same series in double (JIT) or
    calls libbtdf (scalar); the value is rounded to float and multiplied by |cos wo| in
    float: 4 float roundings allow for both and the inputs' normalisation."""
    b = plugin(case)
    pane = b.pane
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(count, 3))
    wis = f32(v / np.linalg.norm(v, axis=1)[:, None])
    v = rng.normal(size=(count, 3))
    wos = f32(v / np.linalg.norm(v, axis=1)[:, None])
    wis[0], wos[0] = [0.0, 0.0, 1.0], [0.3, -0.4, -math.sqrt(0.75)]  # on the axis
    wis[1], wos[1] = [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]
    nch = pane.channels
    for mode, name in ((mi.TransportMode.Importance, "importance"),
                       (mi.TransportMode.Radiance, "radiance")):
        got = eval_values(b, mode, wis, wos)
        worst, nonzero = 0.0, 0
        for k in range(count):
            a = wis[k] / np.linalg.norm(wis[k])
            c = wos[k] / np.linalg.norm(wos[k])
            src, dst = (c, a) if mode == mi.TransportMode.Radiance else (a, c)
            want = ref_f(pane, src, dst) * abs(wos[k][2])
            g = got[k][:nch] if nch == 3 else got[k][:1]
            nonzero += int(np.any(want > 0))
            err = np.max(np.abs(g - want) / (4.0 * EPS32 * want + 1e-30))
            worst = max(worst, float(err))
        check(worst <= 1.0 and nonzero > count // 2,
              "eval %s, %s: %d random direction pairs (%d lit) equal btdf_pane_eval x "
              "|cos wo| within 4 float roundings (worst %.2g of the bound)"
              % (label, name, count, nonzero, worst))


def integral(pane, side, ti, mode, nmu=400, nphi=400):
    """Per channel, the integral over wo of f |cos wo| (importance: light along wi at ti
    on `side`; radiance: light along each wo towards wi) plus the delta, by the midpoint
    rule in (cos theta_o, phi)."""
    mus = (np.arange(nmu) + 0.5) / nmu
    phis = (np.arange(nphi) + 0.5) * (math.pi / nphi)
    other = "back" if side == "front" else "front"
    out = []
    for c in range(pane.channels):
        tot = 0.0
        for part in ("transmission", "reflection"):
            s = 0.0
            for mo in mus:
                to = math.acos(mo)
                if mode == "importance":
                    v = pane.eval_phis(ti, math.pi - to if part == "transmission" else to,
                                       phis, side, part, c)
                elif part == "transmission":  # light on the other face, leaving along wi
                    v = pane.eval_phis(to, math.pi - ti, phis, other, part, c)
                else:
                    v = pane.eval_phis(to, ti, phis, side, part, c)
                s += float(v.sum()) * mo
            tot += s * (1.0 / nmu) * (math.pi / nphi) * 2.0
        spec = float(np.atleast_1d(pane.specular(ti, light=side))[c])
        out.append(tot + spec)
    return out


def mean_weight(b, mode, wi, count, seed):
    ctx = mi.BSDFContext(mode)
    if JIT:
        si = dr.zeros(mi.SurfaceInteraction3f, count)
        si.wi = mi.Vector3f(wi)
        rng = mi.PCG32(size=count, initstate=seed)
        _, w = b.sample(ctx, si, rng.next_float32(), mi.Point2f(rng.next_float32(),
                                                                   rng.next_float32()))
        x = np.array(w).astype(np.float64)  # (3, count)
    else:
        r = random.Random(seed)
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(wi)
        rows = []
        for _ in range(count):
            _, w = b.sample(ctx, si, r.random(), mi.Point2f(r.random(), r.random()))
            rows.append([float(v) for v in w])
        x = np.array(rows).T
    return x.mean(axis=1), x.std(axis=1) / math.sqrt(count), bool(np.all(np.isfinite(x)))


def weight_checks(count):
    """The mean sampled weight f |cos wo| / pdf (and the delta's weight over its
    probability) is an unbiased estimate of the integral: against the midpoint rule on
    400 x 400 cells within 4 standard errors plus the rule's own error, bounded by twice
    its change from 200 x 200 cells."""
    for label, case, angles in (("A", A, ((+1, 0.0), (+1, 40.0), (+1, 75.0), (-1, 0.0),
                                         (-1, 40.0), (-1, 75.0))),
                                ("B", B, ((+1, 30.0), (-1, 60.0)))):
        b = plugin(case)
        pane = b.pane
        for sgn, deg in angles:
            t = math.radians(deg)
            side = "front" if sgn > 0 else "back"
            wi = [math.sin(t), 0.0, sgn * math.cos(t)]
            T, R = pane.albedo(t, light=side)
            for mode in ("importance", "radiance"):
                tm = mi.TransportMode.Importance if mode == "importance" else \
                    mi.TransportMode.Radiance
                want = integral(pane, side, t, mode)
                coarse = integral(pane, side, t, mode, 200, 200)
                m, se, fin = mean_weight(b, tm, wi, count, 11 + int(deg))
                nch = pane.channels
                good = fin
                worst = 0.0
                for c in range(nch):
                    tol = 4.0 * se[c] + 2.0 * abs(want[c] - coarse[c])
                    good &= abs(m[c] - want[c]) <= tol
                    worst = max(worst, abs(m[c] - want[c]) / tol)
                check(good, "mean weight %s, light on the %s at %g deg, %s mode (%d samples):"
                      " %.5f +- %.1g against the integral %.5f (worst %.2g of the bound; "
                      "albedo R + T %.5f)" % (label, side, deg, mode, count, m[0], se[0],
                                              want[0], worst, float(np.atleast_1d(T + R)[0])))


def chi2_checks():
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    def adapter(case, wi, distort=False):
        b = plugin(case)
        ctx = mi.BSDFContext()
        ctx.type_mask = +mi.BSDFFlags.Glossy  # a delta has no density to histogram

        def si_of(n):
            si = dr.zeros(mi.SurfaceInteraction3f, n)
            si.wi = mi.Vector3f(wi)
            return si

        def sample(u, *a):
            bs, _ = b.sample(ctx, si_of(dr.width(u)), u[0], mi.Vector2f(u[1], u[2]))
            return bs.wo, dr.select(bs.pdf > 0.0, mi.Float(1.0), mi.Float(0.0))

        def pdf(wo, *a):
            p = b.pdf(ctx, si_of(dr.width(wo)), wo)
            return p * dr.select(wo.y > 0.0, 1.1, 0.9) if distort else p
        return sample, pdf

    cases = (("A", A, +1, 0.0), ("A", A, +1, 45.0), ("A", A, +1, 80.0), ("A", A, -1, 30.0),
             ("A", A, -1, 70.0), ("B", B, +1, 20.0))
    for label, case, sgn, deg in cases:
        t = math.radians(deg)
        sf, pf = adapter(case, [math.sin(t), 0.0, sgn * math.cos(t)])
        chi = ChiSquareTest(domain=SphericalDomain(), sample_func=sf, pdf_func=pf,
                            sample_dim=3, sample_count=1000000, res=101, ires=8)
        ok = chi.run(0.01, test_count=len(cases) + 1, quiet=True)
        check(ok, "chi2 %s, light on the %s at %g deg: p-value %.3g (1e6 samples, glossy "
              "parts)%s" % (label, "front" if sgn > 0 else "back", deg, chi.p_value,
                            "" if ok else ": " + chi.messages.strip()[-300:]))
    sf, pf = adapter(A, [math.sin(0.5), 0.0, math.cos(0.5)], distort=True)
    chi = ChiSquareTest(domain=SphericalDomain(), sample_func=sf, pdf_func=pf, sample_dim=3,
                        sample_count=1000000, res=101, ires=8)
    check(not chi.run(0.01, test_count=len(cases) + 1, quiet=True),
          "chi2 rejects the pdf distorted by 1 + 0.1 sign(y): p-value %.3g" % chi.p_value)


def furnace_checks(res, spp):
    """A white furnace through Mitsuba's path tracer (MIS: eval, pdf and sample all
    enter): an orthographic camera sees a large sheet at ti, radiance 1 everywhere, one
    bounce. Each pixel estimates the radiance-mode integral of the sheet at ti; for
    model full with no absorption that is R + T = 1 up to the pane's own tolerance, for
    xu-sun it shows the light Eq. 25 loses."""
    for case, sgn, deg in (({"ior": 1.5, "smoothness": 1.0, "model": "full",
                             "paths": 100000}, +1, 0.0),
                           ({"ior": 1.5, "smoothness": 1.0, "model": "full",
                             "paths": 100000}, -1, 60.0),
                           ({"ior": 1.5, "smoothness": 1.0}, +1, 60.0)):
        t = math.radians(deg)
        sc = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
            "sensor": {"type": "orthographic",
                       "to_world": mi.ScalarTransform4f().look_at(
                           origin=[5.0 * math.sin(t), 0.0, 5.0 * sgn * math.cos(t)],
                           target=[0, 0, 0], up=[0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": res, "height": res,
                                "rfilter": {"type": "box"}},
                       "sampler": {"type": "independent", "sample_count": spp}},
            "sheet": {"type": "rectangle",
                      "to_world": mi.ScalarTransform4f().scale([20.0, 20.0, 1.0]),
                      "bsdf": dict(type="btdftab_pane", **case)},
            "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        }
        s = mi.load_dict(sc)
        pane = s.shapes()[0].bsdf().pane
        img = mi.render(s, spp=spp, seed=1)
        a = np.array(img, dtype=np.float64)[..., 0].ravel()
        mean, err = float(a.mean()), float(a.std()) / math.sqrt(len(a))
        side = "front" if sgn > 0 else "back"
        want = integral(pane, side, t, "radiance")[0]
        coarse = integral(pane, side, t, "radiance", 200, 200)[0]
        tol = 4.0 * err + 2.0 * abs(want - coarse)
        T, R = pane.albedo(t, light=side)
        check(abs(mean - want) <= tol and np.all(np.isfinite(a)),
              "white furnace (path, max_depth 2, %dx%d, %d spp), model %s, camera on the %s "
              "at %g deg: mean pixel %.5f +- %.1g against the integral %.5f (allowed %.2g); "
              "the pane's R + T = %.5f" % (res, res, spp, case.get("model", "xu-sun"), side,
                                           deg, mean, err, want, tol,
                                           float(np.atleast_1d(T + R)[0])))


def xml_check():
    sc = mi.load_string("""<scene version="3.0.0">
        <shape type="rectangle"><bsdf type="btdftab_pane">
            <float name="ior" value="1.5"/><float name="smoothness" value="2"/>
            <float name="back" value="5"/><float name="thickness" value="2"/>
            <integer name="nodes" value="40"/><integer name="modes" value="48"/>
        </bsdf></shape></scene>""")
    b = sc.shapes()[0].bsdf()
    check(b.pane.back == 5.0 and b.pane.thickness == 2.0 and "btdftab_pane" in str(b),
          "an XML scene's btdftab_pane (float back, thickness): %s" % str(b))


def error_checks():
    for kw, want in (({"back": "rough"}, "back 'rough'"), ({"ior": 0.8}, "0.8"),
                     ({"thickness": -1.0}, "-1"), ({"model": "foo"}, "model 'foo'"),
                     ({"part": "glass"}, "part 'glass'"), ({"paths": 10}, "'paths'"),
                     ({"smoothness": 0.0}, "smoothness 0")):
        try:
            mi.load_dict(dict(type="btdftab_pane", **kw))
            msg = "(no error)"
        except Exception as e:  # Mitsuba wraps plugin errors
            msg = str(e)
        check(want in msg and "btdftab_pane" in msg,
              "bad parameters %s: the error names the value: %s"
              % (kw, msg.strip().splitlines()[-1][:150]))


if __name__ == "__main__":
    t0 = time.time()
    print("# variant %s, mitsuba %s, drjit %s, libbtdf %s" % (
        VARIANT, mi.__version__, dr.__version__, btdftab.version()))
    eval_checks("A (n = 1.5, s = 3, flat back, a = 0.01/mm)", A, 20000 if JIT else 400, 1)
    eval_checks("B (3 channels, s = 2, back s = 5, 2 mm)", B, 20000 if JIT else 400, 2)
    error_checks()
    xml_check()
    if JIT:
        chi2_checks()
        weight_checks(1000000)
        furnace_checks(64, 64)
    else:
        weight_checks(20000)
    print("# %.1f s" % (time.time() - t0))
    print("%d passed, %d failed" % (passed, failed))
    sys.exit(1 if failed else 0)
