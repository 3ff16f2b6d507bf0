# SPDX-License-Identifier: MIT
"""The `btdftab_pane` BSDF of Mitsuba 3: a pane of glass in air (btdf/btdf_pane.h,
docs/pane.md) drawn as one thin surface, as a frosted shower door, a lamp diffuser or
a window is modelled in a scene: a rough front face, a flat or rough back face, a
thickness and an absorption, with every interreflection inside the glass. Light goes
through without refracting (air on both sides: bs.eta = 1) and leaves from the point
it reached; the pane is laterally infinite and thin (btdf_pane.h).

Frame: Mitsuba's local z is the shape normal, the side of the front face. Light from
z > 0 falls on the front face, from z < 0 on the back face; each side's angles are
taken in the frame of its own face, as btdf_pane.h states them.

Values: the spread part is the series btdf_pane_eval sums (btdf_pane_get_series),
summed here by the same rule in double (JIT variants) or by libbtdf itself (scalar
variants); the delta part of a flat back face (its mirror reflection, light on the
back) is its Fresnel reflectance, as btdf_pane_specular gives it. The system is
reciprocal in the plain sense (air to air), so there is no n^2 between the transport
modes; eval still takes the light as arriving along wo in radiance mode and along wi
in importance mode.

Sampling: a piecewise-constant table of each side's spread part (both parts, per
incidence node in cos theta, cells uniform in cos theta_o and phi), the part chosen in
proportion to its energy (the delta's too), and a share of cosine-distributed draws so
that every direction with a value is sampled.
"""
import math

import btdftab
import drjit as dr
import mitsuba as mi
import numpy as np

from .model import _gather, _jit, _not
from .plugin import _f64, _parse_ior  # plugin.py imports this module only in register()

_classes = {}

# The sampling table: incidence nodes at theta_i = (k + 1/2) 90 / NI degrees (the nearest
# one serves a direction), outgoing cells NMU in cos theta_o times NPH in phi over [0, pi]
# (the BSDF is even in phi; each cell stands for its mirror too).
NI, NMU, NPH = 32, 64, 64
NCELL = NMU * NPH
EPS_COS = 0.1  # the share of cosine-distributed draws within a part


def _frame(src, dst):
    """(front, mui, muo, cph, through) of light arriving along src, leaving along dst, in
    the frame of the lit face: mu's > 0 (double), cph the cosine of the azimuth of dst
    relative to src (pi: forward), through when dst is on the other side."""
    front = src.z > 0.0
    sg = dr.select(front, 1.0, -1.0)
    ax, ay, az = _f64(src.x), _f64(src.y), _f64(src.z * sg)
    bx, by, bz = _f64(dst.x), _f64(dst.y), _f64(dst.z * sg)
    la = dr.sqrt(ax * ax + ay * ay + az * az)
    lb = dr.sqrt(bx * bx + by * by + bz * bz)
    la = dr.select(la > 0.0, la, 1.0)  # a zero vector (invalid lanes) stays zero
    lb = dr.select(lb > 0.0, lb, 1.0)
    ax, ay, az = ax / la, ay / la, az / la
    bx, by, bz = bx / lb, by / lb, bz / lb
    sa = dr.sqrt(ax * ax + ay * ay)
    # src on the axis: its azimuth is taken as 0 (the x axis), as the sampler takes it
    # (the value does not depend on it there: btdf_pane.h's modes vanish at the pole)
    ax = dr.select(sa > 0.0, ax, 1.0)
    ay = dr.select(sa > 0.0, ay, 0.0)
    d = dr.select(sa > 0.0, sa, 1.0) * dr.sqrt(bx * bx + by * by)
    ok = d > 0.0
    dd = dr.select(ok, d, 1.0)  # dst on the axis: phi is undefined and does not matter
    cph = dr.select(ok, (ax * bx + ay * by) / dd, 1.0)
    cph = dr.clip(cph, -1.0, 1.0)
    return front, az, dr.abs(bz), cph, bz < 0.0


class PaneSeries:
    """Every block and channel of a pane's series on the device (JIT variants): values
    summed by the rule of btdf_pane.h (btdf_pane_get_series) in double, in the order
    libbtdf sums them (src/pane/eval.c)."""

    def __init__(self, pane):
        first = pane.series("front", "transmission", 0)
        self.n = len(first["mu"])
        self.M = first["coef"].shape[0]
        self.nodes = first["mu"]
        blocks = []
        for c in range(pane.channels):
            for light in ("front", "back"):
                for part in ("transmission", "reflection"):
                    blocks.append(pane.series(light, part, c)["coef"].ravel())
        self.block = self.M * self.n * self.n
        self.mu = mi.Float64(self.nodes)
        self.coef = mi.Float64(np.concatenate(blocks))
        self.iters = max(1, math.ceil(math.log2(self.n + 1)))

    def _stencil(self, x, active):
        """(k, [4 weights]): 4-point Lagrange at x over the four nodes from k = (the last
        node <= x) - 1, clamped to [0, n - 4]."""
        n = self.n
        lo = mi.Int32(0)
        hi = mi.Int32(n)
        for _ in range(self.iters):  # lo = the count of nodes <= x (nodes ascending)
            act = active & (lo < hi)
            mid = (lo + hi) >> 1
            a = dr.gather(mi.Float64, self.mu, mi.UInt32(mid), act)
            le = act & (a <= x)
            lo = dr.select(le, mid + 1, lo)
            hi = dr.select(act & ~le, mid, hi)
        k = dr.minimum(dr.maximum(lo - 2, 0), n - 4)
        xs = [dr.gather(mi.Float64, self.mu, mi.UInt32(k + a), active) for a in range(4)]
        w = []
        for a in range(4):
            v = mi.Float64(1.0)
            for b in range(4):
                if b != a:  # distinct Gauss nodes: no zero denominator
                    v = v * (x - xs[b]) / (xs[a] - xs[b])
            w.append(v)
        # the modes m >= 1 past the last node: the last node's times r^m, r = sin theta
        # over the last node's (1 - last^2 > 0: Gauss nodes lie inside (0, 1))
        last = float(self.nodes[-1])
        past = x > last
        r = dr.select(past, dr.sqrt(dr.maximum((1.0 - x * x) / (1.0 - last * last), 0.0)),
                      1.0)
        wp = [dr.select(past, 0.0, w[0]), dr.select(past, 0.0, w[1]),
              dr.select(past, 0.0, w[2]), dr.select(past, 1.0, w[3])]
        return k, w, wp, r

    def eval(self, channels, blk, mui, muo, cph, active):
        """[max(0, the cosine sum)] of each channel of `channels`, block blk (UInt32 per
        lane: 2 * back + reflection) at (mui, muo, cos phi); 0 where not active. The
        stencils and the cosines are the same for every channel: made once. The modes
        m >= 1 run in a device loop (dr.while_loop), not unrolled: unrolled, the 48 to
        96 modes of a pane made kernels LLVM took minutes to compile; the operations and
        their order are the same either way."""
        n = self.n
        nn = n * n
        ki, wi0, wi1, ri = self._stencil(mui, active)
        ko, wo0, wo1, ro = self._stencil(muo, active)
        rr = ri * ro
        at = mi.UInt32(ki * n + ko)
        bases = [at + (ch * 4 + blk) * self.block for ch in channels]
        coef = self.coef

        def mode(m, wi, wo, base):  # the 4 x 4 stencil of mode m (UInt32) in one block
            v = mi.Float64(0.0)
            for a in range(4):
                row = base + (m * nn + a * n)
                g = [dr.gather(mi.Float64, coef, row + b, active) for b in range(4)]
                v = v + wi[a] * (wo[0] * g[0] + wo[1] * g[1] + wo[2] * g[2] + wo[3] * g[3])
            return v

        m0 = mi.UInt32(0)
        one = mi.Float64(1.0)
        totals = tuple(mi.Float64(0.0) + mode(m0, wi0, wo0, base) * one for base in bases)
        rm = one * rr  # (ri ro)^m
        c1 = cph

        def body(m, rm, cm, cm_1, totals):
            out = tuple(t + (mode(m, wi1, wo1, base) * rm) * cm
                        for t, base in zip(totals, bases))
            return m + 1, rm * rr, 2.0 * c1 * cm - cm_1, cm, out

        if self.M > 1:
            _, _, _, _, totals = dr.while_loop(
                state=(mi.UInt32(1), rm, c1, one, totals),
                cond=lambda m, rm, cm, cm_1, totals: m < self.M,
                body=body, labels=("m", "rm", "cm", "cm_1", "totals"))
        return [dr.select(active & (t > 0.0), t, 0.0) for t in totals]


class PaneSampler:
    """The sampling table of a pane (both sides, both parts), channel-averaged."""

    def __init__(self, pane, delta_back):
        chs = pane.channels
        mus = (np.arange(NMU) + 0.5) / NMU
        phis = (np.arange(NPH) + 0.5) * (math.pi / NPH)
        dmu, dph = 1.0 / NMU, math.pi / NPH
        pmf = np.zeros((2, NI, 2, NCELL))
        energy = np.zeros((2, NI, 3))  # T, R spread, R delta
        for sd, light in enumerate(("front", "back")):
            for k in range(NI):
                ti = (k + 0.5) * (math.pi / 2.0) / NI
                for pt, part in enumerate(("transmission", "reflection")):
                    w = np.zeros((NMU, NPH))
                    for i, mo in enumerate(mus):
                        to = math.pi - math.acos(mo) if pt == 0 else math.acos(mo)
                        v = sum(pane.eval_phis(ti, to, phis, light, part, c)
                                for c in range(chs)) / chs
                        w[i] = v * mo * dmu * dph * 2.0  # the mirror half too
                    e = float(w.sum())
                    energy[sd, k, pt] = e
                    if e > 0.0:
                        pmf[sd, k, pt] = (w / e).ravel()
                if sd == 1 and delta_back:
                    energy[sd, k, 2] = float(np.mean([btdftab.fresnel_r(n, ti)
                                                      for n in pane.ior]))
        cdf = np.cumsum(pmf, axis=-1)
        cdf[..., -1] = np.where(cdf[..., -1] > 0.0, 1.0, 0.0)  # rounding must not leave a gap
        self.energy_np = energy
        if _jit():
            self.pmf = mi.Float(pmf.ravel())
            self.cdf = mi.Float(cdf.ravel())
            self.energy = mi.Float(energy.ravel())
        else:
            self.pmf = pmf.ravel().tolist()
            self.cdf = cdf.ravel().tolist()
            self.energy = energy.ravel().tolist()
        self.iters = max(1, math.ceil(math.log2(NCELL)))

    @staticmethod
    def node(mu):
        """The incidence node of cos theta_i = mu."""
        t = dr.acos(dr.clip(mu, 0.0, 1.0)) * (2.0 * NI / math.pi)
        if _jit():
            return dr.minimum(mi.UInt32(t), NI - 1)
        return min(int(t), NI - 1)

    def energies(self, sd, k, active):
        base = (sd * NI + k) * 3
        return [_gather(self.energy, base + j, active) for j in range(3)]

    def block(self, sd, k, pt):
        return ((sd * NI + k) * 2 + pt) * NCELL

    def cell_pdf(self, sd, k, pt, muo, cph, active):
        """The table's density of a direction (per solid angle) within part pt."""
        i = dr.minimum(mi.UInt32(muo * NMU) if _jit() else int(muo * NMU), NMU - 1)
        ph = dr.acos(cph)  # cph is clipped to [-1, 1]
        j = dr.minimum(mi.UInt32(ph * (NPH / math.pi)) if _jit() else int(ph * NPH / math.pi),
                       NPH - 1)
        p = _gather(self.pmf, self.block(sd, k, pt) + i * NPH + j, active)
        return p * (NMU * NPH / (2.0 * math.pi))  # / (dmu dphi 2): the mirror half

    def cell_sample(self, sd, k, pt, u, active):
        """(cell index, u): the first cell whose cumulative probability exceeds u."""
        base = self.block(sd, k, pt)
        lo = 0 * k
        hi = lo + NCELL
        for _ in range(self.iters + 1):
            act = active & (lo < hi)
            mid = (lo + hi) >> 1
            a = _gather(self.cdf, base + mid, act)
            le = act & (a <= u)
            lo = dr.select(le, mid + 1, lo)
            hi = dr.select(act & _not(le), mid, hi)
        return dr.minimum(lo, NCELL - 1)


def _make_class():
    class BtdftabPaneBSDF(mi.BSDF):
        """Mitsuba BSDF `btdftab_pane`; parameters in docs/mitsuba3.md."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            if mi.is_polarized:
                raise RuntimeError("btdftab_pane: polarized variants are not supported "
                                   "(variant %s)" % mi.variant())
            part = props.get("part", "both")
            if part not in ("both", "transmission", "reflection"):
                raise ValueError("btdftab_pane: part '%s': must be 'both', 'transmission' "
                                 "or 'reflection'" % part)
            self.part = part
            self.ior = _parse_ior(props.get("ior", "1.5"), "btdftab_pane")
            self.s = float(props.get("smoothness", 3.0))
            back = props.get("back", "smooth")
            if isinstance(back, str) and back.strip() == "smooth":
                back = "smooth"
            else:
                try:
                    back = float(back)
                except ValueError:
                    raise ValueError("btdftab_pane: back '%s': 'smooth', or the back face's "
                                     "smoothness" % back) from None
            model = props.get("model", "xu-sun")
            if model not in btdftab.MODELS:
                raise ValueError("btdftab_pane: model '%s': must be %s"
                                 % (model, ", ".join(btdftab.MODELS)))
            kw = {}
            if model == "full":
                kw = {"paths": int(props.get("paths", btdftab.FULL_PATHS_DEFAULT)),
                      "seed": int(props.get("seed", 1))}
            elif "paths" in props or "seed" in props:
                raise ValueError("btdftab_pane: 'paths' and 'seed' are for model 'full'")
            try:
                self.pane = btdftab.Pane(self.ior if len(self.ior) == 3 else self.ior[0],
                                         self.s, back=back,
                                         thickness=float(props.get("thickness", 4.0)),
                                         absorption=float(props.get("absorption", 0.0)),
                                         k0=float(props.get("k0", 0.7)), model=model,
                                         nodes=int(props.get("nodes", 0)),
                                         modes=int(props.get("modes", 0)), **kw)
            except ValueError as e:
                raise ValueError("btdftab_pane: %s" % e) from None
            self.model, self.back = model, back
            self.channels = self.pane.channels
            if self.channels == 3 and not mi.is_rgb:
                raise RuntimeError("btdftab_pane: three channels need an RGB variant "
                                   "(variant %s)" % mi.variant())
            self.delta = back == "smooth"  # light on the back: its mirror, a delta
            self.series = PaneSeries(self.pane) if _jit() else None
            self.sampler = PaneSampler(self.pane, self.delta)
            self.has_r = part != "transmission"
            self.has_t = part != "reflection"
            sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            comps = []
            self.ci_r = self.ci_t = self.ci_d = -1
            if self.has_r:
                self.ci_r = len(comps)
                comps.append(mi.BSDFFlags.GlossyReflection | sides)
            if self.has_t:
                self.ci_t = len(comps)
                comps.append(mi.BSDFFlags.GlossyTransmission | sides)
            if self.has_r and self.delta:
                self.ci_d = len(comps)
                comps.append(mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.BackSide)
            self.m_components = comps
            flags = comps[0]
            for c in comps[1:]:
                flags = flags | c
            self.m_flags = flags

        # --- values ---------------------------------------------------------------------
        def _f(self, src, dst, active):
            """The spread part f(light along src -> dst) per channel (double), 1/sr."""
            front, mui, muo, cph, through = _frame(src, dst)
            ok = active & (mui > 0.0) & (muo > 0.0)
            if _jit():
                blk = dr.select(front, 0, 2) + dr.select(through, 0, 1)
                blk = mi.UInt32(blk)
                return self.series.eval(range(self.channels), blk, mui, muo, cph, ok)
            if not ok:
                return [0.0] * self.channels
            lib = btdftab.pane._lib()
            sd = 1 if front else 2
            pt = 1 if through else 2
            ti = math.acos(min(mui, 1.0))
            to = math.pi - math.acos(min(muo, 1.0)) if through else math.acos(min(muo, 1.0))
            ph = math.acos(cph)
            return [lib.btdf_pane_eval(self.pane._h, sd, pt, c, ti, to, ph)
                    for c in range(self.channels)]

        def _enabled(self, ctx):
            en_r = self.has_r and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, self.ci_r)
            en_t = self.has_t and ctx.is_enabled(mi.BSDFFlags.GlossyTransmission,
                                                 self.ci_t)
            en_d = self.ci_d >= 0 and ctx.is_enabled(mi.BSDFFlags.DeltaReflection, self.ci_d)
            return bool(en_r), bool(en_t), bool(en_d)

        def _spectrum(self, vals):
            conv = mi.Float if _jit() else float
            if self.channels == 1:
                return mi.UnpolarizedSpectrum(conv(vals[0]))
            return mi.Color3f(*[conv(v) for v in vals])

        def eval(self, ctx, si, wo, active=True):
            en_r, en_t, _ = self._enabled(ctx)
            value = dr.zeros(mi.Spectrum)
            if not (en_r or en_t):
                return value
            wi = si.wi
            through = wi.z * wo.z < 0.0
            on = active & ((through & en_t) | (_not(through) & en_r)) & (wi.z * wo.z != 0.0)
            # light arrives along wo in radiance mode, along wi in importance mode
            src, dst = (wo, wi) if ctx.mode == mi.TransportMode.Radiance else (wi, wo)
            vals = self._f(src, dst, on)
            return dr.select(on, self._spectrum(vals) * dr.abs(wo.z), value)

        # --- sampling -------------------------------------------------------------------
        def _mix(self, wi, en_r, en_t, en_d, active):
            """(sd, k, wi in the lit frame, [P_T, P_R, P_D], eps_T, eps_R) for light along
            wi: each part's probability, in proportion to its energy at the nearest node
            (1/2 each, all cosine, where the node holds none)."""
            front = wi.z > 0.0
            sg = dr.select(front, 1.0, -1.0)
            wl = mi.Vector3f(wi.x, wi.y, wi.z * sg)
            sd = dr.select(front, 0, 1)
            if _jit():
                sd = mi.UInt32(sd)
            k = self.sampler.node(wl.z)
            e = self.sampler.energies(sd, k, active)
            e_t = e[0] if en_t else 0.0
            e_r = e[1] if en_r else 0.0
            e_d = e[2] if en_d else 0.0
            tot = e_t + e_r + e_d
            some = tot > 0.0
            inv = 1.0 / dr.select(some, tot, 1.0)  # tot = 0: the fallback below
            n_on = (1.0 if en_t else 0.0) + (1.0 if en_r else 0.0)
            half = 1.0 / max(n_on, 1.0)
            p_t = dr.select(some, e_t * inv, half if en_t else 0.0)
            p_r = dr.select(some, e_r * inv, half if en_r else 0.0)
            p_d = dr.select(some, e_d * inv, 0.0)
            eps_t = dr.select(e_t > 0.0, EPS_COS, 1.0)  # no table: the cosine alone
            eps_r = dr.select(e_r > 0.0, EPS_COS, 1.0)
            return sd, k, wl, [p_t, p_r, p_d], eps_t, eps_r

        def _pdf(self, wi, wo, en_r, en_t, en_d, active):
            sd, k, wl, p, eps_t, eps_r = self._mix(wi, en_r, en_t, en_d, active)
            _, _, muo, cph, through = _frame(wi, wo)
            muo32 = mi.Float(muo) if _jit() else float(muo)
            cph32 = mi.Float(cph) if _jit() else float(cph)
            on = active & (wi.z != 0.0) & (muo32 > 0.0)
            cos_d = muo32 / math.pi
            q_t = self.sampler.cell_pdf(sd, k, 0, muo32, cph32, on & through)
            q_r = self.sampler.cell_pdf(sd, k, 1, muo32, cph32, on & _not(through))
            pt = p[0] * ((1.0 - eps_t) * q_t + eps_t * cos_d)
            pr = p[1] * ((1.0 - eps_r) * q_r + eps_r * cos_d)
            val = dr.select(through, pt if en_t else 0.0, pr if en_r else 0.0)
            return dr.select(on, val, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            en_r, en_t, en_d = self._enabled(ctx)
            if not (en_r or en_t):
                return mi.Float(0.0) if _jit() else 0.0
            return self._pdf(si.wi, wo, en_r, en_t, en_d, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            en_r, en_t, en_d = self._enabled(ctx)
            if not (en_r or en_t or en_d):
                return bs, dr.zeros(mi.Spectrum)
            wi = si.wi
            sd, k, wl, p, eps_t, eps_r = self._mix(wi, en_r, en_t, en_d, active)
            p_t, p_r, p_d = p
            is_d = sample1 < p_d
            is_t = _not(is_d) & (sample1 < p_d + p_t)
            lo = dr.select(is_d, 0.0, dr.select(is_t, p_d, p_d + p_t))
            width = dr.select(is_d, p_d, dr.select(is_t, p_t, p_r))
            u = dr.clip((sample1 - lo) / dr.select(width > 0.0, width, 1.0), 0.0, 0.99999994)
            eps = dr.select(is_t, eps_t, eps_r)
            cosine = u < eps
            u2 = dr.minimum(dr.maximum(u - eps, 0.0) / dr.maximum(1.0 - eps, 1e-6), 0.99999994)
            # a table cell, a point in it uniform in (cos theta_o, phi), phi's sign from y
            pt = dr.select(is_t, 0, 1)
            if _jit():
                pt = mi.UInt32(pt)
            cell = self.sampler.cell_sample(sd, k, pt, u2, active & _not(cosine) & _not(is_d))
            i = cell // NPH
            j = cell - i * NPH
            muo_c = (mi.Float(i) if _jit() else float(i)) + sample2.x
            muo_c = dr.minimum(muo_c / NMU, 1.0)
            y = sample2.y * 2.0
            neg = y >= 1.0
            fy = dr.select(neg, y - 1.0, y)
            ph = ((mi.Float(j) if _jit() else float(j)) + fy) * (math.pi / NPH)
            ph = dr.select(neg, -ph, ph)
            sti = dr.sqrt(wl.x * wl.x + wl.y * wl.y)
            on_axis = sti > 0.0
            ca = dr.select(on_axis, wl.x / dr.select(on_axis, sti, 1.0), 1.0)
            sa = dr.select(on_axis, wl.y / dr.select(on_axis, sti, 1.0), 0.0)
            cp, sp = dr.cos(ph), dr.sin(ph)
            sto = dr.sqrt(dr.maximum(1.0 - muo_c * muo_c, 0.0))
            d_cell = mi.Vector3f(sto * (ca * cp - sa * sp), sto * (sa * cp + ca * sp), muo_c)
            d_cos = mi.warp.square_to_cosine_hemisphere(sample2)
            d = dr.select(cosine, d_cos, d_cell)
            wo_l = mi.Vector3f(d.x, d.y, dr.select(is_t, -d.z, d.z))
            wo_l = dr.select(is_d, mi.Vector3f(-wl.x, -wl.y, wl.z), wo_l)
            sg = dr.select(wi.z > 0.0, 1.0, -1.0)
            wo = dr.normalize(mi.Vector3f(wo_l.x, wo_l.y, wo_l.z * sg))
            ok = active & (wi.z != 0.0) & (wo_l.z != 0.0)
            bs.wo = wo
            bs.eta = 1.0
            pdf_g = self._pdf(wi, wo, en_r, en_t, en_d, ok & _not(is_d))
            bs.pdf = dr.select(is_d, p_d, pdf_g)
            bs.sampled_component = dr.select(
                is_d, mi.UInt32(max(self.ci_d, 0)),
                dr.select(is_t, mi.UInt32(max(self.ci_t, 0)), mi.UInt32(max(self.ci_r, 0))))
            bs.sampled_type = dr.select(
                is_d, mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                dr.select(is_t, mi.UInt32(+mi.BSDFFlags.GlossyTransmission),
                          mi.UInt32(+mi.BSDFFlags.GlossyReflection)))
            ok &= bs.pdf > 0.0
            # the delta: the flat back's Fresnel reflectance over its probability
            cti = dr.abs(wi.z)
            fr = [mi.fresnel(cti, n)[0] for n in self.ior]
            if self.channels == 1:
                spec = mi.UnpolarizedSpectrum(fr[0])
            else:
                spec = mi.Color3f(*fr)
            v_d = spec / dr.select(p_d > 0.0, p_d, 1.0)
            v_g = self.eval(ctx, si, bs.wo, ok & _not(is_d)) / dr.select(bs.pdf > 0.0,
                                                                           bs.pdf, 1.0)
            value = dr.select(is_d, v_d, v_g)
            return bs, dr.select(ok, value, 0.0)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return ("btdftab_pane[model=%s, part=%s, n=%s, s=%g, back=%s, thickness=%g mm, "
                    "absorption=%g /mm]" % (self.model, self.part, self.ior, self.s,
                                             self.back, self.pane.thickness,
                                             self.pane.absorption))

    return BtdftabPaneBSDF


def register():
    """Registers `btdftab_pane` for the current Mitsuba variant."""
    v = mi.variant()
    if v is None:
        raise RuntimeError("btdftab: call mi.set_variant(...) before register()")
    if v not in _classes:
        _classes[v] = _make_class()
    cls = _classes[v]
    mi.register_bsdf("btdftab_pane", lambda props: cls(props))
    return cls
