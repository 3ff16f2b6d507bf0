# SPDX-License-Identifier: MIT
"""Eq. 25 and the table interpolation rule of btdf/btdf.h, in Dr.Jit operations.

Every function takes the two directions of one query as sines and cosines in the
model's frame (z into the medium the light comes from):
    e_i = (sti, 0, cti), cti >= 0,      e_o = (sto cph, sto sph, cto), cto <= 0,
and works on Python floats (scalar variants) or on Dr.Jit arrays (JIT variants), where
the same code traces into one vectorised kernel. All arithmetic is in double precision
(mi.Float64): the plugin then equals btdf_table_eval to the rounding of its float result.
"""
import math

import drjit as dr
import mitsuba as mi

from . import libbtdf


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


def incident_factor(sti, cti, s, k0):
    """g = V(ti)/cos ti, the incident factor the table rule divides out; 0 at grazing."""
    ok = cti > 0.0
    c = dr.select(ok, cti, 1.0)  # cos ti = 0 is grazing, where g = 0
    return dr.select(ok, shadow_v(sti / c, s, k0) / c, 0.0)


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


def rho_eq25(n, s, k0, sti, cti, sto, cto, cph, sph):
    """Eq. 25 in the stable form of the model notes (section 2), one channel; 0 where no
    facet connects the two directions and at grazing angles, never NaN."""
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
    v = shadow_v(sti / ci, s, k0) * shadow_v(sto / co, s, k0)
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


def rho_r(n, s, k0, sti, cti, str_, ctr, cph, sph):
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
    v = shadow_v(sti / ci, s, k0) * shadow_v(str_ / cr, s, k0)
    r = fr * d * v / (4.0 * ci * cr)
    return dr.select(ok, r, 0.0)


def rho_any(n, s, k0, sti, cti, sto, cto, cph, sph):
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
    v = shadow_v(sti / ci, s, k0) * shadow_v(sto / co, s, k0)
    # transmission: ca Ft chi / (cos ti cos to), chi = n^2 cb/|v|^2, Ft of the facet
    d1 = dr.select(ok, ca + n * cb, 1.0)  # > 0 where used
    d2 = dr.select(ok, n * ca + cb, 1.0)
    ft = 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2))
    f_t = ca * ft * n * n * cb * inv_l * inv_l
    # reflection: Fr / 4 (cos a = ca)
    f_r = 0.25 * fresnel_r(n, dr.select(ok, ca, 1.0))
    r = d * v * dr.select(refl, f_r, f_t) / (ci * co)
    return dr.select(ok, r, 0.0)


class TableRule:
    """The slices of a table (read by libbtdf) on the device, and the rule of btdf/btdf.h."""

    def __init__(self, table):
        self.kind = table.kind
        self.channels = table.channels
        self.ior = list(table.ior)
        self.s = table.smoothness
        self.k0 = table.k0
        self.count = len(table.ti)
        self.ti_min = table.ti[0]
        self.ti_max = table.ti[-1]
        g = [incident_factor(math.sin(t), math.cos(t), self.s, self.k0) for t in table.ti]
        # g at ti = pi/2 exactly: cos(pi/2) = 6e-17 > 0 gives V = exp(-huge) = 0 as in C.
        if _jit():
            f64, u32 = mi.Float64, mi.UInt32
        else:
            f64 = u32 = (lambda a: a)
        self.ti = f64(table.ti)
        self.g = f64(table.ti.__class__("d", g))
        self.nrows, self.ncols = u32(table.nrows), u32(table.ncols)
        self.row_off, self.col_off = u32(table.row_off), u32(table.col_off)
        self.val_off = u32(table.val_off)
        self.rows, self.cols, self.values = f64(table.rows), f64(table.cols), f64(table.values)
        # The chi rule interpolates rho / K at the nodes: their geometry for K, per slice.
        self.chi = (getattr(table, "rule", libbtdf.RULE_PLAIN) == libbtdf.RULE_CHI
                    and self.kind != libbtdf.KIND_GRID)
        if self.chi:
            ad = table.ti.__class__
            self.sti = f64(ad("d", [math.sin(t) for t in table.ti]))
            self.cti = f64(ad("d", [math.cos(t) for t in table.ti]))
            self.srow = f64(ad("d", [math.sin(r) for r in table.rows]))
            self.crow = f64(ad("d", [math.cos(r) for r in table.rows]))
            self.ccol = f64(ad("d", [math.cos(c) for c in table.cols]))
        # Fixed bisection depths: enough for the largest slice and for the slice count.
        self.it_s = max(1, math.ceil(math.log2(max(2, self.count))))
        self.it_r = max(1, math.ceil(math.log2(max(2, max(table.nrows)))))
        self.it_c = max(1, math.ceil(math.log2(max(2, max(table.ncols)))))

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
            for f, sr, cr, cp in ((f00, sa, ca_, pa), (f01, sa, ca_, pb),
                                  (f10, sb, cb_, pa), (f11, sb, cb_, pb)):
                kk = chi_shape(n, sr * cp * sti + cr * cti)
                # K = 0: the node's facet refracts nothing, its rho is 0 and so is rho / K
                fs.append(dr.select(kk > 0.0, f / dr.select(kk > 0.0, kk, 1.0), 0.0))
            f00, f01, f10, f11 = fs
        val = (1.0 - u) * ((1.0 - v) * f00 + v * f01) + u * ((1.0 - v) * f10 + v * f11)
        return dr.select(inside, val, 0.0)

    def eval(self, sti, cti, sto, cto, cph, sph, active=True):
        """rho~ per channel (a list) for the query, by the rule of btdf/btdf.h."""
        recip = self.kind == libbtdf.KIND_FACET_RECIPROCAL
        grid = self.kind == libbtdf.KIND_GRID
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
            g = incident_factor(sti, cti, self.s, self.k0)
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
            out.append(dr.select(valid, v, 0.0))
        return out
