# SPDX-License-Identifier: MIT
"""The models of btdf/btdf.h (xu-sun: Eq. 25; smith; full: smith plus the multiply
scattered series of btdf_full_get_series) and the table interpolation rule, in Dr.Jit
operations.

Every function takes the two directions of one query as sines and cosines in the
model's frame (z into the medium the light comes from):
    e_i = (sti, 0, cti), cti >= 0,      e_o = (sto cph, sto sph, cto), cto <= 0,
and works on Python floats (scalar variants) or on Dr.Jit arrays (JIT variants), where
the same code traces into one vectorised kernel. All arithmetic is in double precision
(mi.Float64): the plugin then equals btdf_table_eval to the rounding of its float result.
The `model` arguments are Python strings, fixed when a kernel is traced.
"""
import array
import math

import drjit as dr
import mitsuba as mi


def _jit():
    return dr.is_jit_v(mi.Float)


def _gather(src, idx, active):
    """src[idx] where active, else 0; src is a Dr.Jit array (JIT) or a Python array."""
    if _jit():
        return dr.gather(type(src), src, idx, active)
    return src[idx] if active else type(src[0])(0)


def _not(mask):
    return ~mask if _jit() else (not mask)


def shadow_v(tan_t, s, k0):
    """The paper's V(t) from |tan t| >= 0: exp(-(k0 tan/s) exp(-s^2/(4 tan^2)))."""
    # tan = 0: exp(-s^2/(4 tan^2)) -> 0 and V -> 1; the floor keeps 1/tan^2 finite.
    t = dr.maximum(tan_t, 1e-150)
    e = dr.exp(-s * s / (4.0 * t * t))
    # A huge tan (grazing) drives V to exp(-inf) = 0, the limit: no NaN arises there.
    return dr.exp(-(k0 * t / s) * e)


def smith_lambda(sn, cs, s):
    """Smith's Lambda of the Beckmann slopes of RMS 2/s for the polar angle t, from sin t,
    cos t >= 0: exp(-a^2) P(a) / (2 a sqrt(pi)), a = s cos t / (2 sin t), with libbtdf's
    polynomial for P (src/model/kernel.h, bt_lambda) and the same floors."""
    # t = 0: a = inf and Lambda = 0; the floor keeps a finite and exp(-a^2) is 0 there
    a = 0.5 * s * cs / dr.maximum(sn, 1e-300)
    # t = 90 deg: Lambda grows as 1/a; the floor keeps it finite (the caller's 1/cos is 0)
    a = dr.minimum(dr.maximum(a, 1e-150), 1e100)
    ap = dr.minimum(a, 6.0)
    u = 1.0 / (1.0 + 0.25 * ap)
    z = (u - 0.7) * (1.0 / 0.3)
    z2 = z * z
    z4 = z2 * z2
    z8 = z4 * z4
    z16 = z8 * z8
    q = ((((1.1867676924093455 + z * -0.023618146227367517) +
           (-0.17886306605641428 + z * -0.10234086534320358) * z2) +
          ((0.0044565090145065149 + z * 0.047190216554424874) +
           (0.039330353917093844 + z * 0.019367418592606416) * z2) * z4) +
         (((0.0063572500040774442 + z * 0.0013011407413532545) +
           (9.1554866108988373e-05 + z * -3.1673794627486539e-05) * z2) +
          ((-8.91187115683128e-06 + z * 1.3020483812005169e-07) +
           (3.8981032682771344e-07 + z * 2.3894428621003025e-08) * z2) * z4) * z8 +
         ((-1.5779711270640086e-08 + z * -1.5679996926558987e-09) +
          (5.7079271508319384e-10 + z * 6.0577447299708143e-11) * z2) * z16)
    pp = q / (1.0 + 1.7724538509055160 * ap + 2.0 * ap * ap)  # divisor >= 1
    ia2 = 1.0 / (a * a)  # a >= 1e-150: no 1/0
    pt = 0.5 * ia2 * (1.0 - ia2 * (1.5 - ia2 * (3.75 - 13.125 * ia2)))
    pv = dr.select(a < 6.0, pp, pt)
    return dr.exp(-(a * a)) * (pv * (0.28209479177387814 / a))


def _log1p(z):
    """log(1 + z), z >= 0, with the rounding of 1 + z put back (as libbtdf's bt_log1p)."""
    w = 1.0 + z
    return dr.log(w) + (z - (w - 1.0)) / w  # w >= 1


def _stirling_tail(r):
    r2 = r * r
    r4 = r2 * r2
    r8 = r4 * r4
    p = (((1.0 / 12 + r2 * (-1.0 / 360)) + (1.0 / 1260 + r2 * (-1.0 / 1680)) * r4) +
         ((1.0 / 1188 + r2 * (-691.0 / 360360)) + (1.0 / 156 + r2 * (-3617.0 / 122400))
          * r4) * r8)
    return r * p


def smith_t_exponent(li, lo):
    """-ln B(1 + li, 1 + lo), the exponent of smith's transmission term G2, as libbtdf
    forms it (bt_smith_t_exponent: Stirling differences, arguments below 9 shifted)."""
    x = dr.maximum(li, lo)
    y = dr.minimum(li, lo)
    mx = x < 9.0
    my = y < 9.0
    px = pxy = py = 1.0
    for k in range(9):
        px = px * dr.select(mx, 1.0 + x + k, 1.0)
        pxy = pxy * dr.select(mx, 2.0 + x + y + k, 1.0)
        py = py * dr.select(my, 1.0 + y + k, 1.0)
    w = 1.0 + x + dr.select(mx, 9.0, 0.0)
    d = 1.0 + y
    wy = 1.0 + y + dr.select(my, 9.0, 0.0)
    rw, rwd, rwy = 1.0 / w, 1.0 / (w + d), 1.0 / wy  # all >= 10: no 1/0
    dxy = ((w - 0.5) * _log1p(d * rw) + d * dr.log(w + d) - d +
           (_stirling_tail(rwd) - _stirling_tail(rw)))
    gy = (wy - 0.5) * dr.log(wy) - wy + 0.91893853320467274 + _stirling_tail(rwy)
    sh = dr.maximum(dxy - gy + dr.log(px * py / pxy), 0.0)  # -ln B >= 0; pxy >= 1
    return dr.select(x > 0.0, sh, 0.0)  # no shadowing at all: B(1, 1) = 1


def shadowing(model, refl, sti, ci, sto, co, s, k0):
    """The facets' shadowing-masking G for (sin ti, cos ti > 0) and (sin to, |cos to| > 0):
    V(ti) V(to) for xu-sun; smith's height-correlated term (full's single scattering) of
    reflection 1/(1 + Lambda_i + Lambda_o) and of transmission B(1 + Lambda_i,
    1 + Lambda_o); refl a mask (or bool) choosing between the two."""
    if model == "xu-sun":
        return shadow_v(sti / ci, s, k0) * shadow_v(sto / co, s, k0)
    li = smith_lambda(sti, ci, s)
    lo = smith_lambda(sto, co, s)
    if refl is True:
        return 1.0 / (1.0 + li + lo)
    g_t = dr.exp(-smith_t_exponent(li, lo))
    if refl is False:
        return g_t
    return dr.select(refl, 1.0 / (1.0 + li + lo), g_t)


def incident_factor(sti, cti, s, k0, model="xu-sun"):
    """g, the incident factor the table rule divides out (V(ti)/cos ti for xu-sun,
    1/((1 + Lambda(ti)) cos ti) for smith); 0 at grazing."""
    ok = cti > 0.0
    c = dr.select(ok, cti, 1.0)  # cos ti = 0 is grazing, where g = 0
    if model == "xu-sun":
        return dr.select(ok, shadow_v(sti / c, s, k0) / c, 0.0)
    return dr.select(ok, 1.0 / ((1.0 + smith_lambda(sti, dr.maximum(cti, 0.0), s)) * c), 0.0)


def smith_dir_factor(sti, cti, sto, cto, s, refl):
    """(1 + Lambda(ti)) G2 of smith, the factor a smith table divides out beside K
    (src/table/table.c, model_dir_factor); cto >= 0 is |cos| of the outgoing direction."""
    li = smith_lambda(sti, dr.maximum(cti, 0.0), s)
    lo = smith_lambda(sto, dr.maximum(cto, 0.0), s)
    ex = _log1p(li + lo) if refl else smith_t_exponent(li, lo)
    return dr.exp(dr.minimum(_log1p(li) - ex, 0.0))


def chi_shape(n, ca):
    """K = cb (ca + n cb)^2 of the chi rule (btdf/btdf.h), cb by Snell's law from ca;
    0 where the facet refracts nothing (ca <= 0, total internal reflection)."""
    sb2 = (1.0 - ca * ca) / (n * n)
    ok = (ca > 0.0) & (sb2 < 1.0)
    cb = dr.sqrt(dr.select(ok, 1.0 - sb2, 0.0))  # 1 - sb2 > 0 where used
    d = ca + n * cb
    return dr.select(ok, cb * d * d, 0.0)


def facet_of(n, sti, cti, sto, cto, cph, sph):
    """(valid, tn, |psi|) of the facet refracting e_i into e_o for index n (btdf/btdf.h)."""
    valid, tn, psi, _ = facet_of_ca(n, sti, cti, sto, cto, cph, sph)
    return valid, tn, psi


def facet_of_ca(n, sti, cti, sto, cto, cph, sph):
    """facet_of and ca = e_i.h of that facet, as btdf_table_eval computes them."""
    vx = sti + n * sto * cph
    vy = n * sto * sph
    vz = cti + n * cto
    sg = dr.select(vz < 0.0, -1.0, 1.0)  # h = sg v/|v| has h_z >= 0
    ca = sg * (sti * vx + cti * vz)
    cb = -sg * (sto * (cph * vx + sph * vy) + cto * vz)
    valid = (ca > 0.0) & (cb > 0.0) & (vz != 0.0)
    hx = sg * vx
    hy = dr.abs(vy)
    hz = sg * vz
    tn = dr.atan2(dr.sqrt(hx * hx + hy * hy), hz)
    psi = dr.atan2(hy, hx)
    ln = dr.sqrt(hx * hx + hy * hy + hz * hz)
    cah = dr.minimum(1.0, ca / dr.select(valid, ln, 1.0))  # |v| > 0 where valid
    return valid, tn, psi, cah


def rho_eq25(n, s, k0, sti, cti, sto, cto, cph, sph, model="xu-sun"):
    """Eq. 25 in the stable form of the model notes (section 2), one channel; 0 where no
    facet connects the two directions and at grazing angles, never NaN. model smith (or
    full's single scattering): smith's G2 in place of V(ti) V(to)."""
    vx = sti + n * sto * cph
    vy = n * sto * sph
    vz = cti + n * cto
    l2 = vx * vx + vy * vy + vz * vz
    ok = (l2 > 0.0) & (cti > 0.0) & (cto < 0.0)
    inv_l = dr.rsqrt(dr.select(l2 > 0.0, l2, 1.0))  # |v| = 0 only for n = 1, refused
    sg = dr.select(vz < 0.0, -1.0, 1.0)
    ca = sg * (sti * vx + cti * vz) * inv_l
    cb = -sg * (sto * (cph * vx + sph * vy) + cto * vz) * inv_l
    ctn = sg * vz * inv_l
    ok &= (ca > 0.0) & (cb > 0.0) & (ctn > 0.0)
    c = dr.select(ok, ctn, 1.0)  # ctn > 0 where used: no division by 0
    tan2 = (vx * vx + vy * vy) * inv_l * inv_l / (c * c)
    d = s * s * dr.exp(-s * s * tan2 / 4.0) / (4.0 * math.pi * c * c * c * c)
    chi = n * n * cb * inv_l * inv_l  # n^2 cos b/(n cos b - cos a)^2, |n cb - ca| = |v|
    d1 = ca + n * cb
    d2 = n * ca + cb  # both > 0 where used
    d1 = dr.select(ok, d1, 1.0)
    d2 = dr.select(ok, d2, 1.0)
    ft = 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2))
    ci = dr.select(ok, cti, 1.0)
    co = dr.select(ok, -cto, 1.0)
    v = shadowing(model, False, sti, ci, sto, co, s, k0)
    r = ca * ft * d * chi * v / (ci * co)
    return dr.select(ok, r, 0.0)


def fresnel_r(n, ca):
    """Fresnel reflectance of a facet at incidence cosine ca > 0 for the index ratio n
    (the medium behind over the medium of the light); 1 past the critical angle (n < 1).
    Formed as libbtdf forms it (MODEL.md section 8), without the cancellation of
    1 - Ft: with dd = n^2 - 1 and g^2 = n^2 cos^2 b = dd + ca^2,
    ca - g = -dd/(ca + g) and n ca - g/n = dd ((n^2 + 1) ca^2 - 1)/(n^2 (n ca + g/n)),
    so Fr keeps its relative accuracy when n is near 1."""
    d = n - 1.0
    dd = d * (2.0 + d)
    g2 = dd + ca * ca
    tir = g2 <= 0.0
    g = dr.sqrt(dr.select(tir, 0.0, g2))
    s1 = ca + g  # > 0 for ca > 0
    p1 = n * ca + g / n  # > 0 for ca > 0
    s1 = dr.select(s1 > 0.0, s1, 1.0)  # ca = 0 only on lanes the caller masks out
    p1 = dr.select(p1 > 0.0, p1, 1.0)
    rs = dd / (s1 * s1)
    rp = dd * ((n * n + 1.0) * ca * ca - 1.0) / (n * n * p1 * p1)
    return dr.select(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def rho_r(n, s, k0, sti, cti, str_, ctr, cph, sph, model="xu-sun"):
    """The reflection of the same facets (MODEL.md section 8), one channel, for the
    reflected direction e_r = (str_ cph, str_ sph, ctr), ctr >= 0, in the light's
    medium: Fr D V(ti) V(tr) / (4 cos ti cos tr) with h = (e_i + e_r)/|e_i + e_r|.
    0 at grazing angles, never NaN."""
    ux = sti + str_ * cph
    uy = str_ * sph
    uz = cti + ctr  # 2 cos a cos tn
    rxy2 = ux * ux + uy * uy
    uz2 = uz * uz
    ok = (cti > 0.0) & (ctr > 0.0) & (uz > 0.0)
    e = 0.25 * s * s * rxy2  # s^2 tan^2 tn / 4 = e / uz^2
    # past this exponent D underflows to 0 anyway; the cut keeps e/uz2 finite
    ok &= e < 746.0 * uz2  # libbtdf's cut (BTDF_EXP_CUT)
    uz2 = dr.select(ok, uz2, 1.0)
    u2 = rxy2 + uz2
    ca = 0.5 * dr.sqrt(u2)  # cos a = |u|/2 > 0
    fr = fresnel_r(n, ca)
    sec2 = u2 / uz2  # 1/cos^2 tn
    d = s * s / (4.0 * math.pi) * sec2 * sec2 * dr.exp(-e / uz2)
    ci = dr.select(ok, cti, 1.0)  # both > 0 where used
    cr = dr.select(ok, ctr, 1.0)
    v = shadowing(model, True, sti, ci, str_, cr, s, k0)
    r = fr * d * v / (4.0 * ci * cr)
    return dr.select(ok, r, 0.0)


def rho_any(n, s, k0, sti, cti, sto, cto, cph, sph, model="xu-sun"):
    """rho (Eq. 25) where cto < 0 and rho_r where cto > 0, in one pass: both are
    D(h) V(ti) V(to) times a facet factor, with h along e_i + k e_o (k = n through the
    surface, 1 back into the light's medium), so a lane evaluates D and the shadowing
    once instead of both formulas. Same values as rho_eq25 and rho_r (double, never NaN)."""
    refl = cto > 0.0
    k = dr.select(refl, 1.0, n)
    vx = sti + k * sto * cph
    vy = k * sto * sph
    vz = cti + k * cto
    rxy2 = vx * vx + vy * vy
    vz2 = vz * vz
    ok = (cti > 0.0) & (cto != 0.0) & (vz2 > 0.0)
    e = 0.25 * s * s * rxy2  # s^2 tan^2 tn / 4 = e / vz^2
    ok &= e < 746.0 * vz2  # past it D underflows to 0 (libbtdf's BTDF_EXP_CUT)
    vz2 = dr.select(ok, vz2, 1.0)  # > 0 where used
    l2 = rxy2 + vz2
    inv_l = dr.rsqrt(l2)
    sg = dr.select(vz < 0.0, -1.0, 1.0)  # h = sg v/|v| has h_z > 0
    ca = sg * (sti * vx + cti * vz) * inv_l
    cbs = sg * (sto * (cph * vx + sph * vy) + cto * vz) * inv_l  # e_o . h
    cb = dr.select(refl, cbs, -cbs)
    ok &= (ca > 0.0) & (cb > 0.0)
    sec2 = l2 / vz2  # 1/cos^2 tn
    d = s * s / (4.0 * math.pi) * sec2 * sec2 * dr.exp(-e / vz2)
    ci = dr.select(ok, cti, 1.0)  # both > 0 where used
    co = dr.select(ok, dr.abs(cto), 1.0)
    v = shadowing(model, refl, sti, ci, sto, co, s, k0)
    # transmission: ca Ft chi / (cos ti cos to), chi = n^2 cb/|v|^2, Ft of the facet
    d1 = dr.select(ok, ca + n * cb, 1.0)  # > 0 where used
    d2 = dr.select(ok, n * ca + cb, 1.0)
    ft = 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2))
    f_t = ca * ft * n * n * cb * inv_l * inv_l
    # reflection: Fr / 4 (cos a = ca)
    f_r = 0.25 * fresnel_r(n, dr.select(ok, ca, 1.0))
    r = d * v * dr.select(refl, f_r, f_t) / (ci * co)
    return dr.select(ok, r, 0.0)


class FullSeries:
    """The multiply scattered part of the model full for one index (btdf_full_get_series
    of a btdftab.Full), on the device: rho_ms(ti, mu, cos phi) summed as btdf/btdf.h
    states it and as libbtdf sums it (src/model/full.c, full_ms)."""

    def __init__(self, full):
        sr = full.series()
        self.nodes = [float(x) for x in sr["node_deg"]]
        self.poly = sr["poly"].tolist()  # constants of the traced kernel
        self.K, self.M = len(self.poly[0]), len(self.poly)
        coef = sr["coef"]  # (nodes, 2, K, M)
        f64 = mi.Float64 if _jit() else (lambda a: a)
        self.coef = f64(array.array("d", coef.ravel().tolist()))
        self.stride = 2 * self.K * self.M
        clip = sr["clip"]  # (nodes, SUB + 1, 2): the clip's energy factor
        self.sub = clip.shape[1] - 1
        self.clip = f64(array.array("d", clip.ravel().tolist()))
        # energy of each side per node: only the constant term integrates to non-zero
        # against mu dmu dphi (orthonormal basis): E = 2 pi a_00 q_00 / 2, q_00 = sqrt 2
        self.energy = [[math.pi * self.poly[0][0][0] * coef[k, h, 0, 0] for h in (0, 1)]
                       for k in range(len(self.nodes))]

    def locate(self, ti_deg):
        """(node a, weight w) as libbtdf's full_locate: the first a with ti <= node[a+1]
        (a + 1 < nodes), w clamped to [0, 1]."""
        nn = len(self.nodes)
        k = mi.UInt32(0) if _jit() else 0
        for j in range(1, nn - 1):
            k = k + dr.select(ti_deg > self.nodes[j], 1, 0)
        lo = self._node(k)
        hi = self._node(k + 1)
        w = dr.clip((ti_deg - lo) / (hi - lo), 0.0, 1.0)  # nodes distinct: hi > lo
        return k, w

    def _node(self, k):
        """node_deg[k] in double (a float32 weight would lose the series' digits)."""
        if not _jit():
            return self.nodes[k]
        v = mi.Float64(0.0)
        for j, x in enumerate(self.nodes):
            v = dr.select(k == j, mi.Float64(x), v)
        return v

    def energies(self, ti_deg):
        """(E_T, E_R) of the multiple scattering at ti, interpolated between the nodes."""
        k, w = self.locate(ti_deg)
        out = []
        for h in (0, 1):
            if not _jit():
                e0, e1 = self.energy[k][h], self.energy[k + 1][h]
            else:
                e0 = e1 = mi.Float64(0.0)
                for j in range(len(self.nodes)):
                    e0 = dr.select(k == j, mi.Float64(self.energy[j][h]), e0)
                    e1 = dr.select(k + 1 == j, mi.Float64(self.energy[j][h]), e1)
            out.append(dr.maximum((1.0 - w) * e0 + w * e1, 0.0))
        return out

    def eval(self, h, ti_deg, mu, cphi, active=True):
        """rho_ms of side h (0 transmission, 1 reflection), mu = |cos t| of the outgoing
        direction; max(0, the series) times the clip's energy factor, as libbtdf
        sums it."""
        k, w = self.locate(ti_deg)
        st = dr.sqrt(dr.maximum(1.0 - mu * mu, 0.0))  # rounding can push mu above 1
        cm = [1.0, cphi]
        for m in range(2, self.M):
            cm.append(2.0 * cphi * cm[m - 1] - cm[m - 2])  # Chebyshev: cos(m phi)
        sm = [1.0]
        for m in range(1, self.M):
            sm.append(sm[m - 1] * st)
        base0 = k * self.stride + h * self.K * self.M
        base1 = base0 + self.stride
        v = 0.0
        for j in range(self.K):
            for m in range(self.M):
                pv = 0.0
                for i in range(self.K - 1, -1, -1):
                    pv = pv * mu + self.poly[m][j][i]
                b = pv * sm[m] * cm[m]
                off = j * self.M + m
                c0 = _gather(self.coef, base0 + off, active)
                c1 = _gather(self.coef, base1 + off, active)
                v = v + b * ((1.0 - w) * c0 + w * c1)
        # the clip's energy factor between its points in w (btdf/btdf.h)
        x = w * self.sub
        q = dr.minimum(dr.floor(x), self.sub - 1)
        u = x - q
        qi = (mi.UInt32(q) if _jit() else int(q))
        at = (k * (self.sub + 1) + qi) * 2 + h
        fac = (1.0 - u) * _gather(self.clip, at, active) + u * _gather(self.clip, at + 2, active)
        return fac * dr.maximum(v, 0.0)


def _node_factors(table, slices):
    """smith tables: each node's model factor per channel (src/table/table.c,
    model_node_factor: the facet's refracted direction, then (1 + Lambda_i) G2), in the
    order of the values; None for xu-sun (factor 1)."""
    if table.model not in ("smith", "full"):  # full's slices are smith's
        return None
    recip = table.kind == "facet-reciprocal"
    s = table.smoothness
    out = array.array("d")
    for ti, rows, cols, vals in slices:
        sti, cti = math.sin(ti), math.cos(ti)
        for r in rows:
            stn, ctn = math.sin(r), math.cos(r)
            for c in cols:
                cpsi = math.cos(c)
                spsi = math.sqrt(max(0.0, 1.0 - cpsi * cpsi))
                for ch in range(table.channels):
                    n = 1.0 / table.ior[ch] if recip else table.ior[ch]
                    f = 0.0
                    ca = stn * cpsi * sti + ctn * cti
                    sb2 = (1.0 - ca * ca) / (n * n)
                    cb = math.sqrt(1.0 - sb2) if ca > 0.0 and sb2 < 1.0 else 0.0
                    if cb > 0.0:  # else no transmitted direction: the node's rho is 0
                        g = ca / n - cb
                        ox = -sti / n + g * stn * cpsi
                        oy = g * stn * spsi
                        oz = -cti / n + g * ctn
                        if oz < 0.0:
                            f = float(smith_dir_factor(sti, cti, math.hypot(ox, oy), -oz, s,
                                                       False))
                    out.append(f)
    return out


class TableRule:
    """The slices of a table (a btdftab.Table, read by libbtdf) on the device, and the
    rule of btdf/btdf.h, in the table's model (from its metadata): xu-sun, smith, or
    full (smith's slices plus the multiply scattered part of the tally the file keeps,
    added at the query's own directions, as src/table/full.c adds it)."""

    def __init__(self, table):
        self.kind = table.kind
        self.model = table.model
        if self.model not in ("xu-sun", "smith", "full"):
            raise ValueError("btdftab: table '%s' holds model '%s': must be xu-sun, smith "
                             "or full" % (table.path, self.model))
        self.single = "smith" if self.model == "full" else self.model  # the slices' rule
        # full: each channel's tally, for the index n of the material whatever the kind
        self.ms = ([FullSeries(table.full(c)) for c in range(table.channels)]
                   if self.model == "full" else None)
        self.channels = table.channels
        self.ior = list(table.ior)
        self.s = table.smoothness
        self.k0 = table.k0
        slices = table.slices()
        if not slices:
            raise ValueError("btdftab: table '%s' has no slices" % table.path)
        ti_l = array.array("d", [sl[0] for sl in slices])
        nrows, ncols = array.array("I"), array.array("I")
        row_off, col_off, val_off = array.array("I"), array.array("I"), array.array("I")
        rows, cols, values = array.array("d"), array.array("d"), array.array("d")
        for ti, r, c, v in slices:
            nrows.append(len(r))
            ncols.append(len(c))
            row_off.append(len(rows))
            col_off.append(len(cols))
            val_off.append(len(values))
            rows.extend(r.tolist())
            cols.extend(c.tolist())
            values.extend(v.ravel().tolist())
        if len(values) >= 2 ** 32:
            raise ValueError("btdftab: table '%s': %d values, more than 32-bit indices "
                             "address" % (table.path, len(values)))
        self.count = len(ti_l)
        self.ti_min = ti_l[0]
        self.ti_max = ti_l[-1]
        g = [float(incident_factor(math.sin(t), math.cos(t), self.s, self.k0, self.single))
             for t in ti_l]
        # g at ti = pi/2 exactly: cos(pi/2) = 6e-17 > 0 gives V = exp(-huge) = 0 as in C.
        if _jit():
            f64, u32 = mi.Float64, mi.UInt32
        else:
            f64 = u32 = (lambda a: a)
        self.ti = f64(ti_l)
        self.g = f64(array.array("d", g))
        self.nrows, self.ncols = u32(nrows), u32(ncols)
        self.row_off, self.col_off = u32(row_off), u32(col_off)
        self.val_off = u32(val_off)
        self.rows, self.cols, self.values = f64(rows), f64(cols), f64(values)
        # The chi rule interpolates rho / K at the nodes: their geometry for K, per slice.
        self.chi = table.rule == "chi" and self.kind != "grid"
        nf = _node_factors(table, slices) if self.chi else None
        self.nodef = f64(nf) if nf is not None else None
        if self.chi:
            ad = array.array
            self.sti = f64(ad("d", [math.sin(t) for t in ti_l]))
            self.cti = f64(ad("d", [math.cos(t) for t in ti_l]))
            self.srow = f64(ad("d", [math.sin(r) for r in rows]))
            self.crow = f64(ad("d", [math.cos(r) for r in rows]))
            self.ccol = f64(ad("d", [math.cos(c) for c in cols]))
        # Fixed bisection depths: enough for the largest slice and for the slice count.
        self.it_s = max(1, math.ceil(math.log2(max(2, self.count))))
        self.it_r = max(1, math.ceil(math.log2(max(2, max(nrows)))))
        self.it_c = max(1, math.ceil(math.log2(max(2, max(ncols)))))

    @staticmethod
    def _bracket(arr, off, m, x, iters, active):
        """i in [0, m-2] with arr[off+i] <= x <= arr[off+i+1] (arr strictly increasing
        over off..off+m-1, x inside); 0 when m = 1."""
        lo = 0 * m  # same type as m
        hi = dr.select(m > 0, m - 1, 0)
        for _ in range(iters):
            act = active & (hi - lo > 1)
            mid = (lo + hi) >> 1
            a = _gather(arr, off + mid, act)
            right = act & (a <= x)
            lo = dr.select(right, mid, lo)
            hi = dr.select(act & _not(right), mid, hi)
        return lo

    def _slice(self, k, x, y, ch, active, n=1.0):
        """Bilinear value of slice k at (x, y), channel ch; 0 outside its node range. Under
        the chi rule, of the reduced values rho / K (n: the slices' index)."""
        ro = _gather(self.row_off, k, active)
        co = _gather(self.col_off, k, active)
        vo = _gather(self.val_off, k, active)
        nr = _gather(self.nrows, k, active)
        nc = _gather(self.ncols, k, active)
        r0 = _gather(self.rows, ro, active)
        r1 = _gather(self.rows, ro + nr - 1, active)
        c0 = _gather(self.cols, co, active)
        c1 = _gather(self.cols, co + nc - 1, active)
        inside = active & (x >= r0) & (x <= r1) & (y >= c0) & (y <= c1)
        i = self._bracket(self.rows, ro, nr, x, self.it_r, inside)
        j = self._bracket(self.cols, co, nc, y, self.it_c, inside)
        mr = inside & (nr > 1)
        mc = inside & (nc > 1)
        xa = _gather(self.rows, ro + i, mr)
        xb = _gather(self.rows, ro + i + 1, mr)
        ya = _gather(self.cols, co + j, mc)
        yb = _gather(self.cols, co + j + 1, mc)
        # rows and columns increase strictly, so xb > xa wherever mr holds
        u = dr.select(mr, (x - xa) / dr.select(mr, xb - xa, 1.0), 0.0)
        v = dr.select(mc, (y - ya) / dr.select(mc, yb - ya, 1.0), 0.0)
        i1 = dr.select(mr, i + 1, i)
        j1 = dr.select(mc, j + 1, j)
        nch = self.channels
        f00 = _gather(self.values, vo + (i * nc + j) * nch + ch, inside)
        f01 = _gather(self.values, vo + (i * nc + j1) * nch + ch, inside)
        f10 = _gather(self.values, vo + (i1 * nc + j) * nch + ch, inside)
        f11 = _gather(self.values, vo + (i1 * nc + j1) * nch + ch, inside)
        if self.chi:
            sti = _gather(self.sti, k, inside)
            cti = _gather(self.cti, k, inside)
            sa = _gather(self.srow, ro + i, inside)
            ca_ = _gather(self.crow, ro + i, inside)
            sb = _gather(self.srow, ro + i1, inside)
            cb_ = _gather(self.crow, ro + i1, inside)
            pa = _gather(self.ccol, co + j, inside)
            pb = _gather(self.ccol, co + j1, inside)
            fs = []
            idx = (vo + (i * nc + j) * nch + ch, vo + (i * nc + j1) * nch + ch,
                   vo + (i1 * nc + j) * nch + ch, vo + (i1 * nc + j1) * nch + ch)
            for q, (f, sr, cr, cp) in enumerate(((f00, sa, ca_, pa), (f01, sa, ca_, pb),
                                                 (f10, sb, cb_, pa), (f11, sb, cb_, pb))):
                kk = chi_shape(n, sr * cp * sti + cr * cti)
                if self.nodef is not None:  # smith: the node's model factor beside K
                    kk = kk * _gather(self.nodef, idx[q], inside)
                # K = 0: the node's facet refracts nothing, its rho is 0 and so is rho / K
                fs.append(dr.select(kk > 0.0, f / dr.select(kk > 0.0, kk, 1.0), 0.0))
            f00, f01, f10, f11 = fs
        val = (1.0 - u) * ((1.0 - v) * f00 + v * f01) + u * ((1.0 - v) * f10 + v * f11)
        return dr.select(inside, val, 0.0)

    def eval(self, sti, cti, sto, cto, cph, sph, active=True):
        """rho~ per channel (a list) for the query, by the rule of btdf/btdf.h."""
        recip = self.kind == "facet-reciprocal"
        grid = self.kind == "grid"
        q_sti, q_cti, q_cto = sti, cti, cto  # the query's own, for full's tally
        if grid:
            x_grid = dr.atan2(sto, cto)  # to in [pi/2, pi]
            y_grid = dr.atan2(dr.abs(sph), cph)  # |phi| folded into [0, pi]
        if recip:  # rho(n; ti, to) = n^2 rho~(1/n; pi - to, pi - ti): swap the directions
            sti, cti, sto, cto = sto, -cto, sti, -cti
        ti = dr.atan2(sti, cti)
        inr = active & (ti >= self.ti_min) & (ti <= self.ti_max)
        if self.count > 1:
            zero, count = (mi.UInt32(0), mi.UInt32(self.count)) if _jit() else (0, self.count)
            k = self._bracket(self.ti, zero, count, ti, self.it_s, inr)
            t0 = _gather(self.ti, k, inr)
            t1 = _gather(self.ti, k + 1, inr)
            w = dr.select(inr, (ti - t0) / dr.select(inr, t1 - t0, 1.0), 0.0)
            g0 = _gather(self.g, k, inr)
            g1 = _gather(self.g, k + 1, inr)
            g = incident_factor(sti, cti, self.s, self.k0, self.single)
        else:
            k = 0 if not _jit() else mi.UInt32(0)
        out = []
        for c in range(self.channels):
            n = 1.0
            if grid:
                valid, x, y = inr, x_grid, y_grid
            else:
                n = 1.0 / self.ior[c] if recip else self.ior[c]
                valid, x, y, ca = facet_of_ca(n, sti, cti, sto, cto, cph, sph)
                valid = valid & inr
                if self.chi:  # the query's K restores rho from the blended rho / K
                    kq = chi_shape(n, ca)
                    if self.nodef is not None:  # and smith's factor of the query itself
                        kq = kq * smith_dir_factor(sti, cti, sto, -cto, self.s, False)
                    valid = valid & (kq > 0.0)
            v = self._slice(k, x, y, c, valid, n)
            if self.count > 1:
                v1 = self._slice(k + 1, x, y, c, valid & (w > 0.0), n)
                # A slice whose g is 0 (ti = 90 deg) holds zeros and says nothing of the
                # reduced value rho/g: the neighbour's stands in (btdf/btdf.h's rule).
                q0 = dr.select(g0 > 0.0, v / dr.select(g0 > 0.0, g0, 1.0), 0.0)
                q1 = dr.select(g1 > 0.0, v1 / dr.select(g1 > 0.0, g1, 1.0), 0.0)
                r0 = dr.select(g0 > 0.0, q0, q1)
                r1 = dr.select(g1 > 0.0, q1, q0)
                v = dr.select(w > 0.0, g * ((1.0 - w) * r0 + w * r1), v)
            if self.chi:
                v = v * kq
            if recip:
                v = self.ior[c] * self.ior[c] * v
            v = dr.select(valid, v, 0.0)
            if self.ms is not None:
                # full: the tally's orders 2+ at the query's directions, also where no
                # facet connects them; 0 outside the slices' incidence range (a
                # reciprocal table covers every ti) and at grazing, as table_add_ms
                mu = dr.abs(q_cto)
                ok = active & (q_cti > 0.0) & (mu > 0.0)
                if not recip:
                    ok = ok & inr
                ti_deg = dr.atan2(q_sti, q_cti) * (180.0 / math.pi)
                if _jit():
                    v = v + dr.select(ok, self.ms[c].eval(0, ti_deg, mu, cph, ok), 0.0)
                elif ok:
                    v = v + self.ms[c].eval(0, ti_deg, mu, cph)
            out.append(v)
        return out
