# SPDX-License-Identifier: MIT
"""The system BSDF of a pane in air (btdf/btdf_pane.h, docs/pane.md), from Python.

    import numpy as np, btdftab
    p = btdftab.Pane(1.5, 3, back="smooth", thickness=4, absorption=0.01)
    p.eval(np.radians(30), np.radians([150, 160]), np.pi)          # light on the front face
    p.eval(np.radians(30), np.radians(40), np.pi, light="back", part="reflection")
    T, R = p.albedo(np.radians([0, 30, 60]))                       # delta parts included

The values are libbtdf's doubles (btdf_pane_eval, btdf_pane_albedo, btdf_pane_specular):
what `btdftab eval --back`, `albedo --back` print, bit for bit.
"""
import ctypes
import math

import numpy as np

from . import (MAX_CHANNELS, BtdfError, _check, _f64, _FullOpts, _ior_params, _library,
               _model_id, _out, _Params)

_SIDES = {"front": 1, "back": 2}  # btdf_pane_side
_PART_IDS = {"transmission": 1, "reflection": 2}  # btdf_part
S_MIN, S_MAX = 1e-3, 1e6  # BTDF_S_MIN, BTDF_S_MAX


class _PaneOpts(ctypes.Structure):
    """btdf_pane_opts of btdf/btdf_pane.h, field for field."""
    _fields_ = [("front", _Params), ("front_smooth", ctypes.c_int),
                ("back_smooth", ctypes.c_int), ("back_smoothness", ctypes.c_double),
                ("thickness_mm", ctypes.c_double), ("absorption_per_mm", ctypes.c_double),
                ("nodes", ctypes.c_int), ("modes", ctypes.c_int), ("threads", ctypes.c_int),
                ("full", ctypes.POINTER(_FullOpts))]


_declared = None


def _lib():
    """libbtdf with the pane's functions declared (once)."""
    global _declared
    lib = _library()
    if _declared is lib:
        return lib
    if not hasattr(lib, "btdf_pane_new"):
        raise BtdfError("this libbtdf has no btdf_pane_new (a pane needs libbtdf 0.4 with "
                        "btdf/btdf_pane.h)")
    d, i, sz, vp, cp = (ctypes.c_double, ctypes.c_int, ctypes.c_size_t, ctypes.c_void_p,
                        ctypes.c_char_p)
    op, dp, ip = (ctypes.POINTER(_PaneOpts), ctypes.POINTER(ctypes.c_double),
                  ctypes.POINTER(ctypes.c_int))

    def f(name, res, *args):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, list(args)

    f("btdf_pane_opts_default", None, op)
    f("btdf_pane_opts_check", i, op, cp, sz)
    f("btdf_pane_new", i, op, ctypes.POINTER(vp), cp, sz)
    f("btdf_pane_free", None, vp)
    f("btdf_pane_size", None, vp, ip, ip)
    f("btdf_pane_seconds_build", d, vp)
    f("btdf_pane_eval", d, vp, i, i, i, d, d, d)
    f("btdf_pane_specular", d, vp, i, i, i, d)
    f("btdf_pane_albedo", None, vp, i, i, d, dp, dp)
    f("btdf_pane_eval_phis", None, vp, i, i, i, d, d, sz, dp, dp)
    if hasattr(lib, "btdf_pane_get_series"):  # from this release on
        f("btdf_pane_get_series", i, vp, i, i, i, ctypes.POINTER(dp), ctypes.POINTER(dp),
          ip, ip)
    _declared = lib
    return lib


def _side(light):
    if light not in _SIDES:
        raise ValueError("light %r: front or back (the face the light falls on)" % (light,))
    return _SIDES[light]


def _part(part):
    if part not in _PART_IDS:
        raise ValueError("part %r: transmission or reflection" % (part,))
    return _PART_IDS[part]


class Pane:
    """A pane in air (btdf_pane_new): the front face of index ior (> 1, one or three
    channels), smoothness and model; the back face flat (back="smooth") or rough with
    smoothness back; thickness in mm (default 4, as the tool's) and absorption per mm
    (default 0). nodes, modes (0: chosen from s), threads (0: all cores; the result does
    not depend on it) as btdf_pane_opts; model "full" takes its tally's paths and seed
    (None: the library's defaults, what the tool uses). The system is built once, in
    the constructor (a second or so at s = 3); evaluate it as often as needed."""

    def __init__(self, ior, smoothness, back="smooth", thickness=4.0, absorption=0.0,
                 k0=0.7, model="xu-sun", nodes=0, modes=0, threads=0, paths=None, seed=None):
        lib = _lib()
        o = _PaneOpts()
        lib.btdf_pane_opts_default(ctypes.byref(o))
        o.front = _ior_params(ior, smoothness, k0, _model_id(model))
        if isinstance(back, str):
            if back != "smooth":
                raise ValueError("back %r: 'smooth', or a smoothness in [%g, %g]"
                                 % (back, S_MIN, S_MAX))
            o.back_smooth, o.back_smoothness = 1, float(smoothness)  # as the tool's
        else:
            b = float(back)
            if not S_MIN <= b <= S_MAX:
                raise ValueError("back %g: 'smooth', or a smoothness in [%g, %g]"
                                 % (b, S_MIN, S_MAX))
            o.back_smooth, o.back_smoothness = 0, b
        o.thickness_mm, o.absorption_per_mm = float(thickness), float(absorption)
        o.nodes, o.modes, o.threads = int(nodes), int(modes), int(threads)
        self._full = None
        if paths is not None or seed is not None:
            if model != "full":
                raise ValueError("paths and seed are the tally's of model 'full', not %r"
                                 % (model,))
            fo = _FullOpts()
            lib.btdf_full_opts_default(ctypes.byref(fo))
            if paths is not None:
                fo.paths = int(paths)
            if seed is not None:
                fo.seed = int(seed)
            fo.threads = int(threads)
            self._full = fo  # kept alive with the options that point at it
            o.full = ctypes.pointer(fo)
        msg = ctypes.create_string_buffer(512)
        if lib.btdf_pane_opts_check(ctypes.byref(o), msg, 512) != 0:
            raise ValueError("Pane: " + msg.value.decode("utf-8", "replace"))
        h = ctypes.c_void_p()
        _check(lib.btdf_pane_new(ctypes.byref(o), ctypes.byref(h), msg, 512),
               "btdf_pane_new", msg)
        self._h = h
        self.channels = o.front.channels
        self.ior = [o.front.ior[c] for c in range(self.channels)]
        self.smoothness, self.k0, self.model = float(smoothness), float(k0), model
        self.back = "smooth" if o.back_smooth else o.back_smoothness
        self.thickness, self.absorption = o.thickness_mm, o.absorption_per_mm

    def size(self):
        """(nodes, modes): the quadrature the system was built on (btdf_pane_size)."""
        n, m = ctypes.c_int(), ctypes.c_int()
        _lib().btdf_pane_size(self._h, ctypes.byref(n), ctypes.byref(m))
        return n.value, m.value

    def seconds_build(self):
        return _lib().btdf_pane_seconds_build(self._h)

    def _map(self, fn, arrs, why):
        """fn(flat index values...) -> channels values, over the broadcast arrays."""
        arrs = _f64(*arrs)
        shape = arrs[0].shape
        flat = [x.reshape(-1) for x in arrs]
        out = np.empty((flat[0].size, self.channels))
        for j in range(out.shape[0]):
            v = [float(x[j]) for x in flat]
            w = why(*v)
            if w:
                raise ValueError("Pane: %s at flat index %d" % (w, j))
            out[j] = fn(*v)
        return _out(out, shape + (3,)) if self.channels == 3 else _out(out[:, 0], shape)

    def eval(self, ti, to, phi, light="front", part="transmission"):
        """The spread part of the system's BSDF (btdf_pane_eval), 1/sr without a cosine,
        radians, in the frame of the lit face: transmission to in [pi/2, pi], reflection
        (part="reflection") to = tr in [0, pi/2]; phi = pi the forward plane. Shape: the
        broadcast of the angles, a last axis of 3 for three channels."""
        sd, pt = _side(light), _part(part)
        lib, h, nch = _lib(), self._h, self.channels
        refl = pt == 2

        def why(a, b, c):
            ok = (0 <= a <= np.pi / 2 and (0 <= b <= np.pi / 2 if refl else
                                           np.pi / 2 <= b <= np.pi) and math.isfinite(c))
            return None if ok else (
                "angles (%r, %r, %r): need ti in [0, pi/2], %s and a finite phi (radians)"
                % (a, b, c, "tr in [0, pi/2]" if refl else "to in [pi/2, pi]"))
        return self._map(lambda a, b, c: [lib.btdf_pane_eval(h, sd, pt, ch, a, b, c)
                                          for ch in range(nch)], (ti, to, phi), why)

    def eval_deg(self, ti, to, phi, light="front", part="transmission"):
        """eval with the angles in degrees, turned into radians as x * pi / 180 as
        `btdftab eval --back` does: its values, bit for bit."""
        a, b, c = _f64(ti, to, phi)
        refl = _part(part) == 2
        bad = ~((a >= 0) & (a <= 90) & ((b >= 0) & (b <= 90) if refl else (b >= 90) & (b <= 180))
                & (c >= -360) & (c <= 360))
        if np.any(bad):
            j = int(np.flatnonzero(bad.reshape(-1))[0])
            raise ValueError("Pane: angles (%r, %r, %r): need ti in [0, 90], %s and phi in "
                             "[-360, 360] degrees at flat index %d"
                             % (float(a.reshape(-1)[j]), float(b.reshape(-1)[j]),
                                float(c.reshape(-1)[j]),
                                "tr in [0, 90]" if refl else "to in [90, 180]", j))
        return self.eval(a * math.pi / 180.0, b * math.pi / 180.0, c * math.pi / 180.0,
                         light=light, part=part)

    def eval_phis(self, ti, to, phi, light="front", part="transmission", channel=0):
        """btdf_pane_eval_phis: eval of one channel at one (ti, to) (radians, as eval) for
        a 1-D array of phi, the interpolation in cos theta done once; values outside the
        domain are 0, as the library gives them."""
        sd, pt = _side(light), _part(part)
        if not 0 <= int(channel) < self.channels:
            raise ValueError("channel %r: 0 to %d" % (channel, self.channels - 1))
        ph = np.ascontiguousarray(np.asarray(phi, dtype=np.float64).reshape(-1))
        out = np.zeros_like(ph)
        dp = ctypes.POINTER(ctypes.c_double)
        _lib().btdf_pane_eval_phis(self._h, sd, pt, int(channel), float(ti), float(to),
                                   ph.size, ph.ctypes.data_as(dp), out.ctypes.data_as(dp))
        return out

    def specular(self, ti, light="front", part="reflection"):
        """The weight of the delta part at ti (btdf_pane_specular): the share of the
        incident power a flat face sends in the mirror (reflection) or straight-through
        (transmission) direction; 0 when there is none."""
        sd, pt = _side(light), _part(part)
        lib, h = _lib(), self._h
        return self._map(lambda a: [lib.btdf_pane_specular(h, sd, pt, ch, a)
                                    for ch in range(self.channels)], (ti,), _ti_why)

    def albedo(self, ti, light="front"):
        """(T, R): the system's hemispherical transmittance and reflectance at ti
        (radians), delta parts included (btdf_pane_albedo)."""
        sd = _side(light)
        lib, h = _lib(), self._h
        t, r = ctypes.c_double(), ctypes.c_double()

        def one(a):
            res = []
            for ch in range(self.channels):
                lib.btdf_pane_albedo(h, sd, ch, a, ctypes.byref(t), ctypes.byref(r))
                res += [t.value, r.value]
            return res
        arrs = _f64(ti)
        shape = arrs[0].shape
        flat = arrs[0].reshape(-1)
        out = np.empty((flat.size, 2 * self.channels))
        for j in range(flat.size):
            w = _ti_why(float(flat[j]))
            if w:
                raise ValueError("Pane.albedo: %s at flat index %d" % (w, j))
            out[j] = one(float(flat[j]))
        pick = (lambda k: _out(out[:, k::2].copy(), shape + (3,))) if self.channels == 3 else \
            (lambda k: _out(out[:, k].copy(), shape))
        return pick(0), pick(1)

    def T(self, ti, light="front"):
        return self.albedo(ti, light)[0]

    def R(self, ti, light="front"):
        return self.albedo(ti, light)[1]

    def series(self, light="front", part="transmission", channel=0):
        """The series btdf_pane_eval sums (btdf_pane_get_series): a dict of mu (nodes,),
        the ascending cos theta nodes in air, and coef (modes, nodes, nodes), the cosine
        coefficients per mode at (incidence node, outgoing node); both copies. The rule
        (4-point Lagrange in mu_i, then mu_o; the stencil from the last node <= x, less
        one, clamped; max(0, the cosine sum)) is btdf_pane.h's."""
        sd, pt = _side(light), _part(part)
        lib = _lib()
        if not hasattr(lib, "btdf_pane_get_series"):
            raise BtdfError("this libbtdf has no btdf_pane_get_series")
        if not 0 <= int(channel) < self.channels:
            raise ValueError("channel %r: 0 to %d" % (channel, self.channels - 1))
        mu, coef = ctypes.POINTER(ctypes.c_double)(), ctypes.POINTER(ctypes.c_double)()
        n, m = ctypes.c_int(), ctypes.c_int()
        _check(lib.btdf_pane_get_series(self._h, sd, pt, int(channel), ctypes.byref(mu),
                                        ctypes.byref(coef), ctypes.byref(n), ctypes.byref(m)),
               "btdf_pane_get_series")
        nn, mm = n.value, m.value
        return {"mu": np.ctypeslib.as_array(mu, shape=(nn,)).copy(),
                "coef": np.ctypeslib.as_array(coef, shape=(mm, nn, nn)).copy()}

    def close(self):
        if getattr(self, "_h", None):
            _lib().btdf_pane_free(self._h)
            self._h = None

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: the process frees it anyway
            pass


def _ti_why(a):
    return None if 0 <= a <= np.pi / 2 else "ti %r: need [0, pi/2] (radians)" % (a,)
