# SPDX-License-Identifier: MIT
"""The `btdftab` BSDF of Mitsuba 3: a rough dielectric interface that transmits by
Eq. 25 of Xu & Sun (2008) or the models smith and full (btdf/btdf.h), from a btdftab
table or from the formulas themselves, and reflects by the companion term of the same
facets (MODEL.md section 8). Everything it takes from libbtdf comes through the
Python package btdftab (tables, parameter checks, full's tally).

Frame: Mitsuba's local z is the shape normal, the "front" side. A table describes light
arriving on the front side, with its index n = (index behind) / (index in front), as
btdftab writes it. Light arriving from behind is rho(1/n), which comes from
`filename_back` when given and otherwise from the front table by the model's
reciprocity rho(1/n; ti, to, phi) = n^-2 rho(n; pi - to, pi - ti, phi).

Transport: the plugin stores the physical BTDF rho(light from a -> b). In radiance mode
(camera paths) light arrives along wo and leaves along wi, so eval gives
rho(wo -> wi) |cos wo|; in importance mode rho(wi -> wo) |cos wo|.

Reflection: rho_r = Fr D V(ti) V(tr) / (4 cos ti cos tr), evaluated from the model
(index n for light arriving in front, 1/n from behind, with total internal reflection
on the facets), in both modes: the tables hold transmission only. It is reciprocal for
xu-sun and smith; it is evaluated for light arriving along wo in radiance mode, along wi
in importance mode, which matters for full. `part` = both (default), transmission (the
transmission-only surface of earlier releases) or reflection.

Models: `model` (mode analytic) is xu-sun (default), smith or full; a table's model is
its own (the file's metadata), and the reflection beside it is of the same model. full
is smith plus the multiply scattered series of a tally made once per index when the
plugin loads (btdftab.Full: `paths`, default 200000, and `seed`, default 1, as
`btdftab eval --model full`; light from behind is the material of index 1/n, a tally of
its own). Sampling then mixes in cosine-distributed directions on the two sides in
proportion to the multiply scattered energy, so the broad lobe is sampled everywhere.
"""
import math

import btdftab
import drjit as dr
import mitsuba as mi

from .model import FullSeries, TableRule, rho_any, rho_eq25, rho_r

_classes = {}


def _jit():
    return dr.is_jit_v(mi.Float)


def _not(mask):
    return ~mask if _jit() else (not mask)


def _f64(x):
    return mi.Float64(x) if _jit() else float(x)


def _to_float(x):
    return mi.Float(x) if _jit() else float(x)


def _angles(a, b):
    """(sti, cti, sto, cto, cph, sph) in double for a (z >= 0) and b (either side; cto
    keeps b's sign), the directions normalised; phi is the azimuth of b relative to a."""
    ax, ay, az = _f64(a.x), _f64(a.y), _f64(a.z)
    bx, by, bz = _f64(b.x), _f64(b.y), _f64(b.z)
    la = dr.sqrt(ax * ax + ay * ay + az * az)
    lb = dr.sqrt(bx * bx + by * by + bz * bz)
    la = dr.select(la > 0.0, la, 1.0)  # a zero vector (invalid lanes) stays zero
    lb = dr.select(lb > 0.0, lb, 1.0)
    ax, ay, az = ax / la, ay / la, az / la
    bx, by, bz = bx / lb, by / lb, bz / lb
    sti = dr.sqrt(ax * ax + ay * ay)
    sto = dr.sqrt(bx * bx + by * by)
    d = sti * sto
    ok = d > 0.0
    dd = dr.select(ok, d, 1.0)  # on the axis phi is undefined and does not matter: 0
    cph = dr.select(ok, (ax * bx + ay * by) / dd, 1.0)
    sph = dr.select(ok, dr.abs(ax * by - ay * bx) / dd, 0.0)
    return sti, az, sto, bz, cph, sph


def _flip(v):
    return mi.Vector3f(v.x, v.y, -v.z)


def _parse_ior(text, who="btdftab"):
    vals = [float(x) for x in str(text).replace(",", " ").split()]
    if len(vals) not in (1, 3):
        raise ValueError("%s: ior '%s': give one index or three (R, G, B)" % (who, text))
    return vals


def _resolve(name):
    try:
        return str(mi.file_resolver().resolve(name))
    except AttributeError:  # older Mitsuba releases
        return str(mi.Thread.thread().file_resolver().resolve(name))


def _make_class():
    class BtdftabBSDF(mi.BSDF):
        """Mitsuba BSDF `btdftab`; parameters in docs/mitsuba3.md."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            if mi.is_polarized:
                raise RuntimeError("btdftab: polarized variants are not supported "
                                   "(variant %s)" % mi.variant())
            part = props.get("part", "both")
            if part not in ("both", "transmission", "reflection"):
                raise ValueError("btdftab: part '%s': must be 'both', 'transmission' or "
                                 "'reflection'" % part)
            self.part = part
            mode = props.get("mode", "table")
            if mode not in ("table", "analytic"):
                raise ValueError("btdftab: mode '%s': must be 'table' or 'analytic'" % mode)
            self.mode = mode
            fname = props.get("filename", "")
            bname = props.get("filename_back", "")
            self.front = self.back = None
            self.files = []
            self.model = "xu-sun"
            if fname:
                t = btdftab.Table(_resolve(fname))
                self.files.append("%s (%s, %s)" % (fname, t.kind, t.model))
                self.ior, self.s, self.k0 = list(t.ior), t.smoothness, t.k0
                self.model = t.model
                for key in ("ior", "smoothness", "k0", "model"):
                    if key in props:
                        raise ValueError("btdftab: '%s' is given by the table '%s'; drop "
                                         "the parameter" % (key, fname))
                if mode == "table":
                    self.front = TableRule(t)
            elif mode == "table":
                raise ValueError("btdftab: mode 'table' needs 'filename' (a table written "
                                 "by btdftab tabulate, .csv or .exr)")
            else:
                self.ior = _parse_ior(props.get("ior", "1.5"))
                self.s = float(props.get("smoothness", 3.0))
                self.k0 = float(props.get("k0", 0.7))
                self.model = props.get("model", "xu-sun")
                if self.model not in btdftab.MODELS:
                    raise ValueError("btdftab: model '%s': must be %s" % (
                        self.model, ", ".join(btdftab.MODELS)))
                # range checks, clear errors
                btdftab.params_check(self.ior, self.s, self.k0, self.model)
            if bname:
                if mode != "table":
                    raise ValueError("btdftab: filename_back is for mode 'table'")
                tb = btdftab.Table(_resolve(bname))
                want = [1.0 / n for n in self.ior]
                if (tb.channels != len(self.ior) or tb.model != self.model
                        or any(abs(a - b) > 1e-6 * b for a, b in zip(tb.ior, want))
                        or abs(tb.smoothness - self.s) > 1e-9 * self.s
                        or abs(tb.k0 - self.k0) > 1e-9):
                    raise ValueError(
                        "btdftab: filename_back '%s' has n = %s, s = %g, k0 = %g, model %s; "
                        "the back of a front table with n = %s needs n = %s and the same "
                        "s, k0 and model (%s)" % (bname, tb.ior, tb.smoothness, tb.k0,
                                                  tb.model, self.ior, want, self.model))
                self.back = TableRule(tb)
                self.files.append("%s (%s, back)" % (bname, tb.kind))
            self.channels = len(self.ior)
            # full: the multiply scattered series of each index, front (n) and back (1/n)
            self.ms_front = self.ms_back = None
            if self.model == "full":
                paths = int(props.get("paths", btdftab.FULL_PATHS_DEFAULT))
                seed = int(props.get("seed", 1))
                if self.front is not None:  # a full table: its own tally for light in front
                    self.ms_front = self.front.ms
                else:
                    self.ms_front = [FullSeries(btdftab.Full(n, self.s, paths, seed))
                                     for n in self.ior]
                if self.back is not None:  # and the back table's for light from behind
                    self.ms_back = self.back.ms
                else:  # the material of index 1/n: a tally made here
                    self.ms_back = [FullSeries(btdftab.Full(1.0 / n, self.s, paths, seed))
                                    for n in self.ior]
            elif "paths" in props or "seed" in props:
                raise ValueError("btdftab: 'paths' and 'seed' are for model 'full'")
            if self.channels == 3 and not mi.is_rgb:
                raise RuntimeError("btdftab: a three-channel table needs an RGB variant "
                                   "(variant %s)" % mi.variant())
            # The model's facets: Beckmann with RMS slope 2/s, drawn by D(m) cos(m) (exact).
            # Mitsuba's visible-normal sampler of Beckmann has lower variance, but its
            # samples follow its pdf only approximately: at n = 1.5, s = 3 the mean weight
            # came out +3.4e-4 and -3.2e-4 off T(ti) at 60 and 80 degrees, 9 and 14
            # standard errors (docs/mitsuba3.md). sample_visible = true selects it.
            visible = bool(props.get("sample_visible", False))
            self.distr = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, 2.0 / self.s,
                                                   visible)
            # Components as Mitsuba's roughdielectric declares them: reflection first,
            # then transmission (non-symmetric: it scales radiance by n^2).
            self.has_r = part != "transmission"
            self.has_t = part != "reflection"
            sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            comps = []
            self.ci_r = self.ci_t = -1
            if self.has_r:
                self.ci_r = len(comps)
                comps.append(mi.BSDFFlags.GlossyReflection | sides)
            if self.has_t:
                self.ci_t = len(comps)
                comps.append(mi.BSDFFlags.GlossyTransmission | sides
                             | mi.BSDFFlags.NonSymmetric)
            self.m_components = comps
            flags = comps[0]
            for c in comps[1:]:
                flags = flags | c
            self.m_flags = flags

        # --- the physical BTDF ------------------------------------------------------
        @property
        def _ss(self):
            """The single-scattering model: full's is smith's."""
            return "smith" if self.model == "full" else self.model

        def _ms(self, c, h, front, ang, active):
            """full's multiply scattered rho of channel c (0 for the other models), side h
            (0 transmission, 1 reflection; int or mask), from the front (index n) or the
            back (1/n) series; 0 at grazing incidence or exit, as libbtdf."""
            if self.ms_front is None:
                return 0.0
            sti, cti, sto, cto, cph, _ = ang
            ti_deg = dr.atan2(sti, cti) * (180.0 / math.pi)
            mu = dr.abs(cto)
            ok = active & (cti > 0.0) & (mu > 0.0)
            if not _jit():  # one lane: the side's series alone
                if not ok:
                    return 0.0
                return (self.ms_front if front else self.ms_back)[c].eval(h, ti_deg, mu, cph)
            vf = self.ms_front[c].eval(h, ti_deg, mu, cph, ok & front)
            vb = self.ms_back[c].eval(h, ti_deg, mu, cph, ok & _not(front))
            return dr.select(ok, dr.select(front, vf, vb), 0.0)

        def _rho(self, src, dst, active):
            """rho(light arriving along src, leaving along dst) per channel (double)."""
            front = src.z > 0.0
            if self.mode == "analytic":
                a = dr.select(front, src, _flip(src))
                b = dr.select(front, dst, _flip(dst))
                ang = _angles(a, b)
                out = []
                for c, n in enumerate(self.ior):
                    ns = dr.select(front, _f64(n), _f64(1.0 / n))  # double, not float
                    v = (rho_eq25(ns, self.s, self.k0, *ang, model=self._ss) +
                         self._ms(c, 0, front, ang, active))
                    out.append(dr.select(active, v, 0.0))
                return out
            if self.back is not None:
                vf = self.front.eval(*_angles(src, dst), active=active & front)
                vb = self.back.eval(*_angles(_flip(src), _flip(dst)),
                                    active=active & _not(front))
                return [dr.select(front, f, b) for f, b in zip(vf, vb)]
            # One table: light from behind by reciprocity, the front table read backwards.
            a = dr.select(front, src, dst)
            b = dr.select(front, dst, src)
            vals = self.front.eval(*_angles(a, b), active=active)
            return [dr.select(front, v, v / (n * n)) for v, n in zip(vals, self.ior)]

        def _rho_r(self, a, b, active):
            """rho_r per channel (double) for a and b on the same side; symmetric."""
            front = a.z > 0.0
            ang = _angles(dr.select(front, a, _flip(a)), dr.select(front, b, _flip(b)))
            out = []
            for c, n in enumerate(self.ior):
                ns = dr.select(front, _f64(n), _f64(1.0 / n))  # double, not float
                v = (rho_r(ns, self.s, self.k0, *ang, model=self._ss) +
                     self._ms(c, 1, front, ang, active))
                out.append(dr.select(active, v, 0.0))
            return out

        def _enabled(self, ctx):
            """(reflection, transmission) enabled by the context and the part."""
            en_r = self.has_r and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, self.ci_r)
            en_t = self.has_t and ctx.is_enabled(mi.BSDFFlags.GlossyTransmission,
                                                 self.ci_t)
            return bool(en_r), bool(en_t)

        def _spectrum(self, vals):
            if self.channels == 1:
                return mi.UnpolarizedSpectrum(_to_float(vals[0]))
            return mi.Color3f(*[_to_float(v) for v in vals])

        # --- Mitsuba interface ----------------------------------------------------------
        def eval(self, ctx, si, wo, active=True):
            en_r, en_t = self._enabled(ctx)
            value = dr.zeros(mi.Spectrum)
            if not (en_r or en_t):
                return value
            wi = si.wi
            if en_t and en_r and self.mode == "analytic":
                # Both lobes in one pass (rho_any): D and the shadowing once per query.
                # rho_r is reciprocal, so the transport mode's order serves both.
                src, dst = (wo, wi) if ctx.mode == mi.TransportMode.Radiance else (wi, wo)
                front = src.z > 0.0
                ang = _angles(dr.select(front, src, _flip(src)),
                              dr.select(front, dst, _flip(dst)))
                vals = []
                h = dr.select(ang[3] > 0.0, 1, 0)  # full: the side's series
                if _jit():
                    h = mi.UInt32(h)
                for c, n in enumerate(self.ior):
                    ns = dr.select(front, _f64(n), _f64(1.0 / n))  # double, not float
                    v = (rho_any(ns, self.s, self.k0, *ang, model=self._ss) +
                         self._ms(c, h, front, ang, active))
                    vals.append(dr.select(active, v, 0.0))
                return dr.select(active, self._spectrum(vals) * dr.abs(wo.z), value)
            if en_t:
                trans = active & (wi.z * wo.z < 0.0)
                if ctx.mode == mi.TransportMode.Radiance:
                    vals = self._rho(wo, wi, trans)  # light arrives along wo
                else:
                    vals = self._rho(wi, wo, trans)
                value = dr.select(trans, self._spectrum(vals) * dr.abs(wo.z), value)
            if en_r:
                refl = active & (wi.z * wo.z > 0.0)
                # light arrives along wo in radiance mode (xu-sun's and smith's rho_r are
                # reciprocal; full's multiply scattered series is so only in the mean)
                src, dst = (wo, wi) if ctx.mode == mi.TransportMode.Radiance else (wi, wo)
                vals = self._rho_r(src, dst, refl)
                value = dr.select(refl, self._spectrum(vals) * dr.abs(wo.z), value)
            return value

        def _pdf_one(self, wi_, wo_, n):
            """Density of wo_ when a facet is drawn from the visible Beckmann normals of
            wi_ (wi_.z > 0) and refracts with index n."""
            v = wi_ + n * wo_
            l2 = dr.squared_norm(v)
            ok = l2 > 0.0
            m = v * (dr.select(v.z < 0.0, -1.0, 1.0) * dr.rsqrt(dr.select(ok, l2, 1.0)))
            cim = dr.dot(wi_, m)
            com = dr.dot(wo_, m)
            ok &= (cim > 0.0) & (com < 0.0) & (wo_.z < 0.0) & (wi_.z > 0.0)
            den = cim + n * com  # = +-|v|, nonzero where ok
            den = dr.select(ok, den, 1.0)
            jac = n * n * dr.abs(com) / (den * den)  # Walter et al. 2007, Eq. 17
            return dr.select(ok, self.distr.pdf(wi_, m) * jac, 0.0), cim

        def _pdf_r(self, wi_, wo_):
            """(density of wo_ reflected off a facet drawn for wi_, cos of wi_ to the
            facet): both above the surface, h = (wi_ + wo_)/|wi_ + wo_|."""
            h = wi_ + wo_
            l2 = dr.squared_norm(h)
            ok = (l2 > 0.0) & (wi_.z > 0.0) & (wo_.z > 0.0)
            h = h * dr.rsqrt(dr.select(ok, l2, 1.0))  # |h| = 0 only where masked out
            cim = dr.dot(wi_, h)
            ok &= cim > 0.0
            jac = 1.0 / (4.0 * dr.select(ok, cim, 1.0))  # Walter et al. 2007, Eq. 14
            return dr.select(ok, self.distr.pdf(wi_, h) * jac, 0.0), cim

        @staticmethod
        def _fresnel(cim, n):
            """The facet's Fresnel reflectance (float, Mitsuba's), the probability of
            choosing the reflection when both lobes are sampled."""
            return mi.fresnel(cim, n)[0]

        def _side(self, wi):
            sg = dr.select(wi.z < 0.0, -1.0, 1.0)
            front = wi.z > 0.0
            return sg, front

        def _ms_mix(self, wi_, front, en_r, en_t):
            """full: (P, pT), the probability of drawing a cosine-distributed direction
            for the multiply scattered lobe and, then, of drawing it through the surface:
            the lobe's energies at ti (channel 0's series), with floors so that both
            stay sampled (P in [0.02, 0.9]; pT in [0.1, 0.9] when both sides are on)."""
            ti_deg = dr.atan2(dr.sqrt(wi_.x * wi_.x + wi_.y * wi_.y), wi_.z) * (180.0 / math.pi)
            ef = self.ms_front[0].energies(ti_deg)
            eb = self.ms_back[0].energies(ti_deg)
            e_t = dr.select(front, ef[0], eb[0]) if en_t else 0.0
            e_r = dr.select(front, ef[1], eb[1]) if en_r else 0.0
            e = e_t + e_r
            big_p = _to_float(dr.clip(e, 0.02, 0.9))
            if en_t and en_r:
                p_t = dr.clip(e_t / dr.select(e > 0.0, e, 1.0), 0.1, 0.9)  # e = 0: 1/2
                p_t = dr.select(e > 0.0, p_t, 0.5)
            else:
                p_t = 1.0 if en_t else 0.0
            return big_p, _to_float(p_t)

        def pdf(self, ctx, si, wo, active=True):
            en_r, en_t = self._enabled(ctx)
            zero = mi.Float(0.0) if _jit() else 0.0
            if not (en_r or en_t):
                return zero
            both = en_r and en_t  # then the lobe is chosen by the facet's Fresnel
            wi = si.wi
            sg, front = self._side(wi)
            wi_ = mi.Vector3f(wi.x, wi.y, wi.z * sg)
            wo_ = mi.Vector3f(wo.x, wo.y, wo.z * sg)
            out = zero
            if en_t:
                p = 0.0
                for n in self.ior:
                    ns = dr.select(front, n, 1.0 / n)
                    pc, cim = self._pdf_one(wi_, wo_, ns)
                    if both:
                        pc = pc * (1.0 - self._fresnel(cim, ns))
                    p = p + pc
                p = p / self.channels  # one channel's index is drawn uniformly
                out = dr.select(active & (wi.z * wo.z < 0.0), p, out)
            if en_r:
                p, cim = self._pdf_r(wi_, wo_)
                if both:
                    f = 0.0
                    for n in self.ior:
                        f = f + self._fresnel(cim, dr.select(front, n, 1.0 / n))
                    p = p * (f / self.channels)
                out = dr.select(active & (wi.z * wo.z > 0.0), p, out)
            if self.ms_front is not None:  # the cosine-distributed part of the mixture
                big_p, p_t = self._ms_mix(wi_, front, en_r, en_t)
                side_p = dr.select(wo_.z < 0.0, p_t, 1.0 - p_t)
                pc = dr.select(active & (wi.z != 0.0), side_p * dr.abs(wo_.z) / math.pi, 0.0)
                out = (1.0 - big_p) * out + big_p * pc
            return out

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            en_r, en_t = self._enabled(ctx)
            if not (en_r or en_t):
                return bs, dr.zeros(mi.Spectrum)
            wi = si.wi
            sg, front = self._side(wi)
            wi_ = mi.Vector3f(wi.x, wi.y, wi.z * sg)
            n = self.ior[0]
            u1 = sample1
            ms = False
            if self.ms_front is not None:  # full: the cosine part of the mixture first
                big_p, p_t = self._ms_mix(wi_, front, en_r, en_t)
                ms = sample1 < big_p
                # what is left of sample1, uniform again (P in [0.02, 0.9]: no 1/0)
                u1 = dr.select(ms, sample1 / big_p, (sample1 - big_p) / (1.0 - big_p))
                u1 = dr.minimum(u1, 0.99999994)  # the rounding must not reach 1
            u = u1
            if self.channels == 3:  # draw the channel whose facets refract the ray
                c = dr.minimum(mi.UInt32(u1 * 3.0), 2) if _jit() else min(int(u1 * 3), 2)
                n = dr.select(c == 0, self.ior[0], dr.select(c == 1, self.ior[1], self.ior[2]))
                u = u1 * 3.0 - c  # what is left of sample1 chooses the lobe
            n = dr.select(front, n, 1.0 / n)
            m, _ = self.distr.sample(wi_, sample2)
            cim = dr.dot(wi_, m)
            # The lobe: reflection with the facet's Fresnel reflectance (pdf() uses the
            # same), always or never when one lobe alone is enabled (u < 1 <= 2).
            if en_r and en_t:
                reflect = u < self._fresnel(cim, n)
            else:
                reflect = u < (2.0 if en_r else -1.0)
            ok = active & (wi.z != 0.0) & (cim > 0.0)
            # transmission: refraction through m; s2 >= 1 is total internal reflection
            inv = 1.0 / n
            s2 = inv * inv * (1.0 - cim * cim)
            ct = dr.sqrt(dr.maximum(1.0 - s2, 0.0))
            wt_ = -inv * wi_ + (inv * cim - ct) * m
            # reflection: the mirror image of wi_ about m
            wr_ = 2.0 * cim * m - wi_
            wo_ = dr.select(reflect, wr_, wt_)
            ok &= dr.select(reflect, wr_.z > 0.0, (s2 < 1.0) & (wt_.z < 0.0))
            if self.ms_front is not None:
                d = mi.warp.square_to_cosine_hemisphere(sample2)
                through = u1 < p_t
                wm_ = mi.Vector3f(d.x, d.y, dr.select(through, -d.z, d.z))
                wo_ = dr.select(ms, wm_, wo_)
                reflect = dr.select(ms, _not(through), reflect)
                ok = dr.select(ms, active & (wi.z != 0.0) & (d.z > 0.0), ok)
            wo = dr.normalize(mi.Vector3f(wo_.x, wo_.y, wo_.z * sg))
            bs.wo = dr.select(ok, wo, mi.Vector3f(0.0, 0.0, -1.0) * sg)
            bs.pdf = dr.select(ok, self.pdf(ctx, si, bs.wo, ok), 0.0)
            bs.eta = dr.select(ok & _not(reflect), n, 1.0)
            bs.sampled_component = dr.select(reflect, mi.UInt32(max(self.ci_r, 0)),
                                             mi.UInt32(max(self.ci_t, 0)))
            bs.sampled_type = dr.select(reflect, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                        mi.UInt32(+mi.BSDFFlags.GlossyTransmission))
            ok &= bs.pdf > 0.0
            value = self.eval(ctx, si, bs.wo, ok) / dr.select(ok, bs.pdf, 1.0)
            return bs, dr.select(ok, value, 0.0)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return ("btdftab[mode=%s, model=%s, part=%s, n=%s, s=%g, k0=%g, files=%s]"
                    % (self.mode, self.model, self.part, self.ior, self.s, self.k0,
                       self.files or "none"))

    return BtdftabBSDF


def register():
    """Registers the plugins `btdftab` and `btdftab_pane` (the thin sheet, pane.py) for
    the current Mitsuba variant (call it again after mi.set_variant switches to another
    one)."""
    v = mi.variant()
    if v is None:
        raise RuntimeError("btdftab: call mi.set_variant(...) before register()")
    if v not in _classes:
        _classes[v] = _make_class()
    cls = _classes[v]
    mi.register_bsdf("btdftab", lambda props: cls(props))
    from . import pane  # the thin sheet, btdftab_pane (imported here: it imports this module)
    pane.register()
    return cls
