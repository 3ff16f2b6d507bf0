# SPDX-License-Identifier: MIT
"""python_pkg.py BTDFTAB: the Python package btdftab against the btdftab tool, bit for bit.

Run in a venv where `pip install .` put the package (.ci/run does), or with the
checkout's python/ on PYTHONPATH and a build folder beside it. Every value the package
returns is compared with the tool's output at 17 significant digits, which names one
double: parsed back, the two must be equal, not close. The tool takes degrees and turns
them into radians as x * pi / 180 (tools/btdftab.c), so the radian forms are given
the same doubles; Eq. 25 itself the tool evaluates in degrees (btdf_rho_deg), which
the package's rho_deg is. Prints "N passed, N failed".
"""
import math
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import btdftab

BT = os.path.abspath(sys.argv[1])
passed = failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok %d - %s" % (passed, what))
    else:
        failed += 1
        print("not ok - %s" % what)


def tool(*args, stdin=None):
    r = subprocess.run([BT] + [str(a) for a in args], input=stdin, capture_output=True,
                       text=True)
    if r.returncode != 0:
        raise RuntimeError("btdftab %s: exit %d: %s" % (" ".join(map(str, args)),
                                                       r.returncode, r.stderr))
    return r.stdout


def rows_of(text):
    return np.array([[float(v) for v in ln.replace(",", " ").split()]
                     for ln in text.splitlines() if ln.strip()])


def same(a, b):
    """Equal doubles, shape for shape (no NaN can occur: the library never returns one)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and bool(np.all(a == b))


def rounding_bound(f_deg, n, s, a, b, c, dom):
    """How far the radian form may differ from the degree form at each point: the
    degree form reduces its angles exactly, the radian form gets x * pi / 180 rounded
    (half an ulp, about 1.1e-16 relative, plus the library's own reduction of a radian
    angle: a few ulps). rho moves by |theta d(rho)/d(theta)| times that relative
    change, summed over the three angles; the slopes are central differences of the
    degree form over 1e-5 degrees. Bound: 16 ulps of rho itself plus 16 ulps of angle
    through each slope (16: the rounding of the angles and of rho's few dozen
    operations, with a margin of 2 over the 8 they sum to at most here)."""
    eps = np.finfo(np.float64).eps
    h = 1e-5
    val = f_deg(n, s, a, b, c)
    slope = np.zeros_like(val)
    for k, x in enumerate((a, b, c)):
        lo, hi = [list((a, b, c)) for _ in range(2)]
        # inside the domain dom[k] = (low, high) at its ends: one-sided there
        lo[k], hi[k] = np.maximum(x - h, dom[k][0]), np.minimum(x + h, dom[k][1])
        d = (f_deg(n, s, *hi) - f_deg(n, s, *lo)) / np.maximum(hi[k] - lo[k], h)
        slope += np.abs(x * d)  # d(rho) per unit relative change of the angle
    return 16 * eps * (np.abs(val) + slope)


DOM_T = ((0, 90), (90, 180), (-1e9, 1e9))  # the domains in degrees (btdf.h)
DOM_R = ((0, 90), (0, 90), (-1e9, 1e9))


def rad(x):
    return np.asarray(x, dtype=np.float64) * math.pi / 180.0  # as the tool does


print("# package %s, library %s (%s)" % (btdftab.__file__, btdftab.library_path(),
                                         btdftab.version()))
# Whatever way the packages were installed (a wheel lists its files one by one), every
# module of the checkout is there: btdftab and the Mitsuba plugin beside it.
import importlib.util  # noqa: E402
_src = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python")
_gone = []
for _pkg in ("btdftab", "btdftab_mitsuba"):
    _spec = importlib.util.find_spec(_pkg)
    _have = set(os.listdir(list(_spec.submodule_search_locations)[0])) if _spec else set()
    _gone += ["%s/%s" % (_pkg, f) for f in sorted(os.listdir(os.path.join(_src, _pkg)))
              if f.endswith(".py") and f not in _have]
check(not _gone, "the installed packages hold every module of the checkout%s"
      % (" (missing: %s)" % ", ".join(_gone) if _gone else ""))
rng = np.random.default_rng(29)
N = 200
ti = np.concatenate([[0, 0, 30, 45, 89.9, 90], rng.uniform(0, 90, N)])
to = np.concatenate([[180, 170, 150, 120, 90.5, 90], rng.uniform(90, 180, N)])
phi = np.concatenate([[180, 90, 180, 0, 180, 180], rng.uniform(0, 360, N)])
tr = 180 - to
stdin = "".join("%.17g %.17g %.17g\n" % v for v in zip(ti, to, phi))
stdin_r = "".join("%.17g %.17g %.17g\n" % v for v in zip(ti, tr, phi))
mats = [(1.5, 3), (1.4, 1), (0.6666667, 6), (1.5, 100), (1.0001, 3), (1.5, 0.3)]

# Eq. 25 and its reflection, angles in degrees as the tool reads them
for n, s in mats:
    want = rows_of(tool("eval", "--ior", n, "-s", s, stdin=stdin))[:, 0]
    check(same(btdftab.rho_deg(n, s, ti, to, phi), want),
          "rho_deg n = %g, s = %g: %d values equal btdftab eval's" % (n, s, len(ti)))
    want = rows_of(tool("eval", "--ior", n, "-s", s, "--part", "reflection", stdin=stdin_r))
    check(same(btdftab.rho_r_deg(n, s, ti, tr, phi), want[:, 0]),
          "rho_r_deg n = %g, s = %g: equal btdftab eval --part reflection's" % (n, s))
    # rho_r in radians takes the tool's own radians for the reflection (btdf_rho_r_deg
    # and btdf_eval_r share the formula past the angles: compared, not assumed)
    got = btdftab.rho_r(n, s, rad(ti), rad(tr), rad(phi))
    bound = rounding_bound(btdftab.rho_r_deg, n, s, ti, tr, phi, DOM_R)
    err = np.abs(got - want[:, 0])
    check(bool(np.all(err <= bound)),
          "rho_r (radians) n = %g, s = %g: within the angles' rounding of the degree form "
          "(worst error / bound %.2g)" % (n, s, (err / np.maximum(bound, 1e-300)).max()))

# three channels: the index broadcasts against the angles
want = rows_of(tool("eval", "--ior", "1.51,1.52,1.53", "-s", 3, stdin=stdin))
got = btdftab.rho_deg(np.array([1.51, 1.52, 1.53]), 3, ti[:, None], to[:, None],
                      phi[:, None])
check(same(got, want), "rho_deg with ior (3,) against angles (N, 1): shape (N, 3), "
      "equal the tool's three channels")

# rho in radians: the degree form reduces its angles exactly, the radian one gets them
# rounded to a double, so the two agree to the rounding_bound; and the array call is
# bit for bit the scalar calls.
for n, s in mats:
    want = rows_of(tool("eval", "--ior", n, "-s", s, stdin=stdin))[:, 0]
    got = btdftab.rho(n, s, rad(ti), rad(to), rad(phi))
    bound = rounding_bound(btdftab.rho_deg, n, s, ti, to, phi, DOM_T)
    err = np.abs(got - want)
    check(bool(np.all(err <= bound)),
          "rho (radians) n = %g, s = %g: within the angles' rounding of btdftab eval "
          "(worst error / bound %.2g)" % (n, s, (err / np.maximum(bound, 1e-300)).max()))
    one = np.array([btdftab.rho(n, s, float(a), float(b), float(c))
                    for a, b, c in zip(rad(ti), rad(to), rad(phi))])
    check(same(got, one), "rho n = %g, s = %g: the array call equals the scalar calls" % (n, s))
    grid = btdftab.rho([[n], [n]], s, rad(ti), rad(to), rad(phi))
    check(same(grid, np.stack([got, got])), "rho n = %g: ior (2, 1) against angles (N,) "
          "gives (2, N)" % n)

# T, R, Ft and R + T against albedo --digits 17 (radians: the tool's x * pi / 180)
ang = np.array([0, 10, 30, 45, 60, 80, 89.9, 90])
for n, s in mats:
    w = rows_of("\n".join(tool("albedo", "--digits", 17, "--ior", n, "-s", s,
                               *ang).splitlines()[1:]))
    a = rad(ang)
    check(same(btdftab.T(n, s, a), w[:, 1]), "T n = %g, s = %g equals albedo's" % (n, s))
    check(same(btdftab.fresnel_t(n, a), w[:, 2]), "fresnel_t n = %g equals albedo's Ft" % n)
    check(same(btdftab.R(n, s, a), w[:, 3]), "R n = %g, s = %g equals albedo's" % (n, s))
    check(same(btdftab.albedo(n, s, a), w[:, 4]), "albedo n = %g, s = %g equals R + T" % (n, s))

def series_at(sr, a, b, c, side=0):
    """rho_ms of a Full.series() at (ti, to or tr, phi) degrees, summed as btdf/btdf.h
    writes it, and the sum of the magnitudes its rounding acts on (each coefficient times
    its basis function evaluated with |poly| in place of poly): with polynomials of
    degree 7 orthonormal on [0, 1] the terms cancel, so the rounding of the sum is
    relative to that magnitude, not to rho_ms."""
    nodes, poly, coef = sr["node_deg"], sr["poly"], sr["coef"]
    k = 0
    while k < len(nodes) - 2 and a > nodes[k + 1]:
        k += 1
    w = min(1.0, max(0.0, (a - nodes[k]) / (nodes[k + 1] - nodes[k])))
    mu = abs(math.cos(math.radians(b)))
    st = math.sqrt(max(0.0, 1.0 - mu * mu))
    total = mag = 0.0
    for j in range(btdftab.SERIES_K):
        for m in range(btdftab.SERIES_M):
            cf = (1 - w) * coef[k, side, j, m] + w * coef[k + 1, side, j, m]
            bas = st ** m * math.cos(m * math.radians(c))
            total += cf * bas * np.polyval(poly[m, j][::-1], mu)
            mag += abs(cf * bas) * np.polyval(np.abs(poly[m, j][::-1]), mu)
    fac = clip_factor(sr, k, w, side)
    return fac * max(0.0, total), fac * mag


def clip_factor(sr, k, w, side):
    """The clip's energy factor of btdf/btdf.h at interval k, weight w, side h."""
    x = w * btdftab.SERIES_SUB
    q = min(int(x), btdftab.SERIES_SUB - 1)
    u = x - q
    return (1 - u) * sr["clip"][k, q, side] + u * sr["clip"][k, q + 1, side]


# The models smith and full (model=...), against btdftab eval|albedo --model, bit for
# bit. full's tally is deterministic (btdf/btdf.h: fixed streams, fixed order), and the
# package makes it with the tool's defaults (200000 paths, seed 1), so the same doubles.
for model, ms in (("smith", mats), ("full", [(1.5, 1), (0.6666667, 3)])):
    for n, s in ms:
        want = rows_of(tool("eval", "--model", model, "--ior", n, "-s", s, stdin=stdin))
        check(same(btdftab.rho_deg(n, s, ti, to, phi, model=model), want[:, 0]),
              "rho_deg model %s n = %g, s = %g: %d values equal btdftab eval --model %s's"
              % (model, n, s, len(ti), model))
        got = btdftab.rho(n, s, rad(ti), rad(to), rad(phi), model=model)
        f_deg = lambda n_, s_, a, b, c: btdftab.rho_deg(n_, s_, a, b, c, model=model)  # noqa
        bound = rounding_bound(f_deg, n, s, ti, to, phi, DOM_T)
        if model == "full":
            # btdf_full_rho turns its radians back into degrees (x * 180/pi, a few ulps
            # of each angle), and the series' cancelling terms (series_at) amplify such
            # a change of mu beyond what its smooth slope shows: 16 ulps of the summed
            # magnitudes on top (40 terms of 8-term Horner sums, a margin of 2 over the
            # 8 ulps of their worst rounding).
            sr = btdftab.Full(n, s).series()
            mag = np.array([series_at(sr, *v)[1] for v in zip(ti, to, phi)])
            bound = bound + 16 * np.finfo(np.float64).eps * mag
        err = np.abs(got - want[:, 0])
        check(bool(np.all(err <= bound)),
              "rho (radians) model %s n = %g, s = %g: within the angles' rounding of "
              "btdftab eval (worst error / bound %.2g)"
              % (model, n, s, (err / np.maximum(bound, 1e-300)).max()))
        want = rows_of(tool("eval", "--model", model, "--ior", n, "-s", s, "--part",
                            "reflection", stdin=stdin_r))
        check(same(btdftab.rho_r_deg(n, s, ti, tr, phi, model=model), want[:, 0]),
              "rho_r_deg model %s n = %g, s = %g: equal btdftab eval --part reflection's"
              % (model, n, s))
        w = rows_of("\n".join(tool("albedo", "--model", model, "--digits", 17, "--ior", n,
                                   "-s", s, *ang).splitlines()[1:]))
        a = rad(ang)
        check(same(btdftab.T(n, s, a, model=model), w[:, 1]) and
              same(btdftab.R(n, s, a, model=model), w[:, 3]) and
              same(btdftab.albedo(n, s, a, model=model), w[:, 4]),
              "T, R, R + T model %s n = %g, s = %g equal btdftab albedo --model %s's"
              % (model, n, s, model))
# xu-sun named is the default, bit for bit
check(same(btdftab.rho(1.5, 3, rad(ti), rad(to), rad(phi), model="xu-sun"),
           btdftab.rho(1.5, 3, rad(ti), rad(to), rad(phi))),
      "model='xu-sun' is the default")
# Full.series rebuilds btdf_full_rho_deg and _rho_r_deg by the formula btdf/btdf.h states
# for them: summed here in another order than the library's, so equal to 16 ulps of the
# magnitudes summed (series_at), plus 16 ulps of rho itself (smith's part).
f = btdftab.Full(1.5, 1)
sr = f.series()
worst = 0.0
for side, fn, fs, outs in ((0, f.rho_deg, btdftab.rho_deg, to), (1, f.rho_r_deg,
                                                                  btdftab.rho_r_deg, tr)):
    for a_, b_, c_ in list(zip(ti, outs, phi))[6:86]:
        ms, mag = series_at(sr, a_, b_, c_, side)
        want1 = fn(a_, b_, c_)
        got = fs(1.5, 1, a_, b_, c_, model="smith") + ms
        worst = max(worst, abs(got - want1) / (16 * np.finfo(np.float64).eps *
                                                (mag + abs(want1)) + 1e-300))
check(worst <= 1.0, "Full.series: smith + the series as btdf/btdf.h writes it equals "
      "btdf_full_rho_deg and btdf_full_rho_r_deg (worst error / bound %.2g)" % worst)
st = f.info()
check(st["nodes"] == len(sr["node_deg"]) and st["paths"] == 200000,
      "Full.info: %d ladder nodes, %d paths, %.2f s" % (st["nodes"], st["paths"],
                                                        st["seconds"]))

W = tempfile.mkdtemp()
# tables: one written by the tool, read by the package; one built by the package
q = rng.uniform(0, 1, (60, 3)) * [80, 89, 180] + [0, 90.5, 0]
qin = "".join("%.17g %.17g %.17g\n" % tuple(v) for v in q)
for ext in ("csv", "exr"):
    path = os.path.join(W, "t." + ext)
    try:
        tool("tabulate", "-q", "--ior", 1.5, "-s", 3, "--tolerance", "1e-2", "-o", path)
    except RuntimeError as e:
        if ext == "exr" and "OpenEXR" in str(e):
            print("# .exr: this build has no OpenEXR (%s)" % str(e).strip())
            continue
        raise
    want = rows_of(tool("eval", "--table", path, stdin=qin))[:, 0]
    t = btdftab.open(path)
    check(t.kind == "facet" and t.ior == [1.5] and t.smoothness == 3 and len(t) > 0,
          ".%s table: kind, n, s, node count read" % ext)
    check(same(t.eval(rad(q[:, 0]), rad(q[:, 1]), rad(q[:, 2])), want),
          "Table.eval on the tool's .%s table equals btdftab eval --table" % ext)
both = os.path.join(W, "both.csv")
tool("tabulate", "-q", "--ior", 1.5, "-s", 3, "--tolerance", "1e-2", "--part", "both",
     "-o", both)
qr = np.column_stack([q[:, 0], 180 - q[:, 1], q[:, 2]])
want = rows_of(tool("eval", "--table", both, "--part", "reflection",
                    stdin="".join("%.17g %.17g %.17g\n" % tuple(v) for v in qr)))[:, 0]
t = btdftab.open(both)
check(t.parts == "both" and same(t.eval(rad(qr[:, 0]), rad(qr[:, 1]), rad(qr[:, 2]),
                                        part="reflection"), want),
      "Table.eval part reflection equals btdftab eval --table --part reflection")
# built by the package: the same table as the tool's (same nodes), written and read back
tb = btdftab.build(1.5, 3, tolerance=1e-2)
mine = os.path.join(W, "mine.csv")
tb.write(mine)
want = rows_of(tool("eval", "--table", os.path.join(W, "t.csv"), stdin=qin))[:, 0]
check(len(tb) == len(btdftab.open(os.path.join(W, "t.csv"))) and
      same(btdftab.open(mine).eval(rad(q[:, 0]), rad(q[:, 1]), rad(q[:, 2])), want),
      "build(1.5, 3, tolerance=1e-2): the nodes and values of btdftab tabulate's table")
# a smith table: the model read from the file's metadata
sm = os.path.join(W, "smith.csv")
tool("tabulate", "-q", "--model", "smith", "--ior", 1.5, "-s", 3, "--tolerance", "1e-2",
     "-o", sm)
want = rows_of(tool("eval", "--table", sm, stdin=qin))[:, 0]
t = btdftab.open(sm)
check(t.model == "smith" and same(t.eval(rad(q[:, 0]), rad(q[:, 1]), rad(q[:, 2])), want),
      "a smith table: Table.model 'smith', Table.eval equals btdftab eval --table")
tb = btdftab.build(1.5, 3, tolerance=1e-2, model="smith")
check(tb.model == "smith" and len(tb) == len(t),
      "build(model='smith'): the nodes of btdftab tabulate --model smith (%d)" % len(tb))
# a table of full (smith's slices and the tally, which the reader rebuilds): built by
# the package as the tool builds it (30 degrees: the tool's x * pi / 180), the same
# values as btdftab eval --table on the tool's own table
fu = os.path.join(W, "full.csv")
tool("tabulate", "-q", "--model", "full", "--ior", 1.5, "-s", 3, "--tolerance", "1e-2",
     "--theta-i", "0:30", "-o", fu)
qf = q * [30 / 80, 1, 1]
want = rows_of(tool("eval", "--table", fu,
                    stdin="".join("%.17g %.17g %.17g\n" % tuple(v) for v in qf)))[:, 0]
tb = btdftab.build(1.5, 3, tolerance=1e-2, model="full", ti_range=(0, 30 * math.pi / 180))
mine = os.path.join(W, "mine_full.csv")
tb.write(mine)
t = btdftab.open(mine)
check(tb.model == "full" and t.model == "full" and len(t) == len(btdftab.open(fu)) and
      same(t.eval(rad(qf[:, 0]), rad(qf[:, 1]), rad(qf[:, 2])), want),
      "build(model='full'): btdftab tabulate --model full's table, read back with its tally")
# Table.full: the tally the file keeps, the one the tool made with its defaults
fs_file = t.full(0).series()
fs_own = btdftab.Full(1.5, 3).series()
check(same(fs_file["coef"], fs_own["coef"]) and same(fs_file["node_deg"], fs_own["node_deg"])
      and btdftab.open(os.path.join(W, "t.csv")).full(0) is None,
      "Table.full: a full table's tally has the coefficients of Full(1.5, 3), the tool's "
      "defaults; a xu-sun table has none")
# a .bsdf written by the tool
bsdf = os.path.join(W, "t.bsdf")
tool("tabulate", "-q", "--ior", 1.5, "-s", 3, "--tolerance", "5e-2", "-o", bsdf)
want = rows_of(tool("eval", "--table", bsdf, stdin=qin))[:, 0]
f = btdftab.open(bsdf)
check(isinstance(f, btdftab.Bsdf) and f.eta == 1.5 and f.channels == 1 and
      same(f.eval(rad(q[:, 0]), rad(q[:, 1]), rad(q[:, 2])), want),
      "Bsdf.eval (light entering) equals btdftab eval --table on a .bsdf")

# Panes (btdftab.Pane over btdf_pane.h) against btdftab eval --back and albedo --back
# --digits 17, bit for bit: the same options make the same system (the build does not
# depend on the thread count), the same degrees the same radians (x * pi / 180, as
# eval_deg and rad() turn them).
pq = slice(0, 60)  # 60 rows each: every pane is built once by the package, once per call
ti_p, to_p, phi_p, tr_p = ti[pq], to[pq], phi[pq], tr[pq]
st_p = "".join("%.17g %.17g %.17g\n" % v for v in zip(ti_p, to_p, phi_p))
st_pr = "".join("%.17g %.17g %.17g\n" % v for v in zip(ti_p, tr_p, phi_p))
panes = [(dict(ior=1.5, smoothness=1, back="smooth", thickness=2, absorption=0.1),
          ["--ior", 1.5, "-s", 1, "--back", "smooth", "--thickness", 2, "--absorption", 0.1]),
         (dict(ior=1.5, smoothness=1, back=2, thickness=2, absorption=0.1),
          ["--ior", 1.5, "-s", 1, "--back", 2, "--thickness", 2, "--absorption", 0.1]),
         (dict(ior=[1.4, 1.5, 1.6], smoothness=1, back="smooth"),
          ["--ior", "1.4,1.5,1.6", "-s", 1, "--back", "smooth"])]
for kw, args in panes:
    pn = btdftab.Pane(**kw)
    name = " ".join(map(str, args))
    for light in ("front", "back"):
        want = rows_of(tool("eval", *args, "--light", light, stdin=st_p))
        got = pn.eval_deg(ti_p, to_p, phi_p, light=light)
        got = got if got.ndim == 2 else got[:, None]
        check(same(got, want) and same(pn.eval(rad(ti_p), rad(to_p), rad(phi_p), light=light),
                                       pn.eval_deg(ti_p, to_p, phi_p, light=light)),
              "Pane(%s).eval light %s: %d values equal btdftab eval %s --light %s's"
              % (kw, light, want.size, name, light))
        want = rows_of(tool("eval", *args, "--light", light, "--part", "reflection",
                            stdin=st_pr))
        got = pn.eval_deg(ti_p, tr_p, phi_p, light=light, part="reflection")
        got = got if got.ndim == 2 else got[:, None]
        check(same(got, want), "Pane(%s).eval light %s part reflection: equal btdftab eval "
              "--back --part reflection's" % (kw, light))
    w = rows_of("\n".join(tool("albedo", *args, "--digits", 17, *ang).splitlines()[1:]))
    nch = pn.channels
    cols = w[:, 1:].reshape(len(ang), nch, 2, 3)  # per channel: front T R R+T, back T R R+T
    good = True
    for k, light in enumerate(("front", "back")):
        T_, R_ = pn.albedo(rad(ang), light=light)
        T_, R_ = (T_, R_) if nch == 3 else (T_[:, None], R_[:, None])
        good &= same(T_, cols[:, :, k, 0]) and same(R_, cols[:, :, k, 1]) and \
            same(T_ + R_, cols[:, :, k, 2])
    check(good, "Pane(%s).albedo front and back: T, R, R + T equal btdftab albedo %s "
          "--digits 17" % (kw, name))
# the delta of a flat back's mirror, light on the back: its Fresnel reflectance exactly
# (btdf_pane.h: a flat face's own mirror); none from the rough front, none transmitted
pn = btdftab.Pane(1.5, 3, back="smooth")
a = rad(ang)
check(same(pn.specular(a, light="back"), btdftab.fresnel_r(1.5, a)) and
      not np.any(pn.specular(a, light="front")) and
      not np.any(pn.specular(a, light="back", part="transmission")),
      "Pane.specular: a flat back's mirror is Fresnel's R, the rough front has none")
# Pane.series: the rule of btdf_pane.h, summed here in numpy, gives Pane.eval (other
# order of the same terms: 1e-12 of the value and of the largest coefficient)


def pane_rule(sr, mui, muo, phi):
    mu, c = sr["mu"], sr["coef"]
    n = len(mu)

    def stencil(x):
        k = min(max(int(np.searchsorted(mu, x, side="right")) - 2, 0), n - 4)
        w = [np.prod([(x - mu[k + b]) / (mu[k + a] - mu[k + b]) for b in range(4) if b != a])
             for a in range(4)]
        # past the last node mode m is the last node's times r^m (sin theta over its)
        wp = [0, 0, 0, 1] if x > mu[-1] else w
        r = math.sqrt((1 - x * x) / (1 - mu[-1] ** 2)) if x > mu[-1] else 1.0
        return k, np.array(w), np.array(wp), r
    ki, wi, wpi, ri = stencil(mui)
    ko, wo, wpo, ro = stencil(muo)
    cm = np.einsum("a,b,mab->m", wpi, wpo, c[:, ki:ki + 4, ko:ko + 4])
    cm = cm * (ri * ro) ** np.arange(len(cm))
    cm[0] = np.einsum("a,b,ab->", wi, wo, c[0, ki:ki + 4, ko:ko + 4])
    return max(0.0, float(np.sum(cm * np.cos(np.arange(len(cm)) * phi))))


pr = btdftab.Pane(1.5, 2, back=5, absorption=0.02, nodes=32, modes=40)
worst = 0.0
for light in ("front", "back"):
    for part in ("transmission", "reflection"):
        sr = pr.series(light, part)
        cmax = float(np.max(np.abs(sr["coef"])))
        for a, t, c in ((10, 40, 170), (35, 12, 90), (70, 60, 180), (0, 85, 0), (88, 3, 45),
                        (0.3, 50, 120), (40, 0.2, 30), (0, 0, 0)):
            to = 180 - t if part == "transmission" else t
            v = float(pr.eval(rad(a), rad(to), rad(c), light=light, part=part))
            r = pane_rule(sr, math.cos(rad(a)), math.cos(rad(t)), rad(c))
            worst = max(worst, abs(v - r) / (1e-12 * abs(v) + 1e-12 * cmax))
check(worst <= 1.0 and pr.series("back", "reflection")["coef"].shape == (40, 32, 32),
      "Pane.series: its coefficients summed by btdf_pane.h's rule give Pane.eval on every "
      "side and part (worst %.2g of the bound)" % worst)
for call, word in ((lambda: btdftab.Pane(1.0, 3), "n = 1"),
                   (lambda: btdftab.Pane(1.5, 3, back="rough"), "rough"),
                   (lambda: btdftab.Pane(1.5, 3, back=1e9), "1e+09"),
                   (lambda: btdftab.Pane(1.5, 3, thickness=-1), "-1"),
                   (lambda: pn.eval_deg(30, 60, 0), "60"),
                   (lambda: pn.eval(0.5, 0.5, 0, part="reflection", light="side"), "side"),
                   (lambda: pn.albedo(2.0), "2.0")):
    try:
        call()
        check(False, "bad pane input raises ValueError (%s)" % word)
    except ValueError as e:
        check(word in str(e), "bad pane input raises ValueError naming %s: %s" % (word, e))

# bad input: ValueError naming the value
for call, word in ((lambda: btdftab.rho(1.5, 3, 2.0, 2.5, 0), "2.0"),
                   (lambda: btdftab.rho(1, 3, 0, 3, 0), "n = 1"),
                   (lambda: btdftab.T(1.5, -1, 0), "-1"),
                   (lambda: btdftab.rho_deg(1.5, 3, 30, 60, 0), "60"),
                   (lambda: btdftab.rho(1.5, 3, 0, 3, 0, model="walter"), "walter"),
                   (lambda: btdftab.T(1.5, 3, 0, model="smth"), "smth"),
                   (lambda: btdftab.rho_deg(1.5, 3, 30, 60, 0, model="full"), "60"),
                   (lambda: btdftab.build((1.49, 1.5, 1.51), 3, model="full", format="bsdf"),
                    "three indices")):
    try:
        call()
        check(False, "bad input raises ValueError (%s)" % word)
    except ValueError as e:
        check(word in str(e), "bad input raises ValueError naming %s: %s" % (word, e))
try:
    btdftab.open(os.path.join(W, "none.csv"))
    check(False, "a missing table raises BtdfError")
except btdftab.BtdfError as e:
    check("none.csv" in str(e), "a missing table raises BtdfError: %s" % e)

shutil.rmtree(W)
print("%d passed, %d failed" % (passed, failed))
sys.exit(1 if failed else 0)
