# SPDX-License-Identifier: MIT
"""btdftab: Eq. 25 of Xu & Sun (2008), its reflection, the models smith and full, and
their tables, from Python.

A thin layer over libbtdf (ctypes): every number comes from the C library, bit for bit.
The functions are spelled as the C API and take numpy arrays (or numbers), which
broadcast against each other; angles in radians (the *_deg forms take degrees, as the
btdftab tool does), conventions of btdf/btdf.h: theta_i in [0, pi/2], theta_o in
[pi/2, pi], phi = pi the forward (specular) plane, rho in 1/sr without a cosine factor.

    import numpy as np, btdftab
    ti = np.radians([0, 30, 60])
    btdftab.rho(1.5, 3, ti, np.radians(150), np.pi)   # Eq. 25 at three angles
    btdftab.rho(1.5, 3, ti, np.radians(150), np.pi, model="full")
    btdftab.T(1.5, 3, ti), btdftab.R(1.5, 3, ti)        # hemispherical integrals
    t = btdftab.build(1.5, 3, tolerance=1e-2)         # a table; t.write("glass.csv")
    btdftab.open("glass.bsdf").eval(ti, np.radians(150), np.pi)
    btdftab.Pane(1.5, 3, back="smooth", thickness=4).eval(ti, np.radians(150), np.pi)

model: "xu-sun" (Eq. 25, the default), "smith" (the height-correlated Smith term of
the same facets) or "full" (smith plus the light scattered two or more times, from a
tally made once per material: paths and seed as btdf_full_opts, the defaults those
of `btdftab eval --model full`; see Full). Tables (.csv, .exr) hold any of the three
(a table of full keeps its tally, which the reader rebuilds); a .bsdf any of them (full with one index).

Bad parameters or angles raise ValueError naming the value and what is allowed; a
failed library call raises BtdfError with the library's message.
"""
import ctypes
import ctypes.util
import os

import numpy as np

__all__ = ["params_check", "rho", "rho_deg", "rho_r", "rho_r_deg", "T", "R", "albedo", "fresnel_t",
           "fresnel_r", "Table", "Bsdf", "Full", "open", "build", "version", "BtdfError",
           "library_path", "MODELS", "Pane"]

MAX_CHANNELS = 3
_KINDS = {0: "facet", 1: "grid", 2: "facet-reciprocal", 3: "facet-reflection"}
_PARTS = {"transmission": 1, "reflection": 2, "both": 3}
_RULES = {0: "plain", 1: "chi", 2: "fresnel"}
MODELS = ("xu-sun", "smith", "full")  # btdf_model: 0, 1, 2
_MODEL_IDS = {name: k for k, name in enumerate(MODELS)}
FULL_PATHS_DEFAULT = 200000  # BTDF_FULL_PATHS_DEFAULT
SERIES_K, SERIES_M, SERIES_NODES, SERIES_SUB = 8, 5, 33, 8  # btdf_full_series of btdf/btdf.h
_STATUS_EDOMAIN = None  # set from the library (btdf_strerror) on load


class BtdfError(RuntimeError):
    """A libbtdf call failed; the message names the call, the status and the reason."""


class _Params(ctypes.Structure):
    _fields_ = [("channels", ctypes.c_int),
                ("ior", ctypes.c_double * MAX_CHANNELS),
                ("smoothness", ctypes.c_double),
                ("k0", ctypes.c_double),
                ("model", ctypes.c_int)]  # btdf_model: 0 = xu-sun, what ctypes zero-fills


class _Slice(ctypes.Structure):
    _fields_ = [("ti", ctypes.c_double), ("nrows", ctypes.c_size_t),
                ("ncols", ctypes.c_size_t), ("rows", ctypes.POINTER(ctypes.c_double)),
                ("cols", ctypes.POINTER(ctypes.c_double)),
                ("values", ctypes.POINTER(ctypes.c_double))]


_PROGRESS = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t,
                             ctypes.c_size_t)


class _FullOpts(ctypes.Structure):
    _fields_ = [("paths", ctypes.c_uint64), ("seed", ctypes.c_uint64),
                ("threads", ctypes.c_int)]


class _FullAlbedos(ctypes.Structure):
    _fields_ = [(k, ctypes.c_double) for k in ("T", "R", "T1", "R1", "Tms", "Rms",
                                               "Tms_se", "Rms_se")]


class _FullStats(ctypes.Structure):
    _fields_ = [("nodes", ctypes.c_int), ("paths", ctypes.c_uint64),
                ("seconds", ctypes.c_double), ("lost", ctypes.c_double),
                ("order1_gap", ctypes.c_double)]


class _FullSeries(ctypes.Structure):
    _fields_ = [("nodes", ctypes.c_int),
                ("node_deg", ctypes.c_double * SERIES_NODES),
                ("poly", ctypes.c_double * (SERIES_M * SERIES_K * SERIES_K)),
                ("coef", ctypes.c_double * (SERIES_NODES * 2 * SERIES_K * SERIES_M)),
                ("clip", ctypes.c_double * (SERIES_NODES * (SERIES_SUB + 1) * 2))]


class _TableOpts(ctypes.Structure):
    """btdf_table_opts of btdf/btdf.h, field for field (filled by btdf_table_opts_default)."""
    _fields_ = [("params", _Params), ("ti_min", ctypes.c_double),
                ("ti_max", ctypes.c_double), ("kind", ctypes.c_int),
                ("tolerance", ctypes.c_double), ("metric", ctypes.c_int),
                ("grid_ti", ctypes.c_size_t), ("grid_to", ctypes.c_size_t),
                ("grid_phi", ctypes.c_size_t), ("max_samples", ctypes.c_size_t),
                ("max_bytes", ctypes.c_size_t), ("threads", ctypes.c_int),
                ("to_min", ctypes.c_double), ("to_max", ctypes.c_double),
                ("phi_min", ctypes.c_double), ("phi_max", ctypes.c_double),
                ("progress", _PROGRESS), ("progress_user", ctypes.c_void_p),
                ("estimate", ctypes.c_int), ("part", ctypes.c_int)]


def _candidates():
    env = os.environ.get("BTDFTAB_LIBRARY")
    if env:
        yield env
        return  # an explicit choice is not second-guessed
    here = os.path.dirname(os.path.abspath(__file__))
    for name in sorted(os.listdir(here)):  # a wheel carries the library in the package
        if name.startswith("libbtdf") and ".so" in name:
            yield os.path.join(here, name)
    try:
        from . import _installed  # written by meson install
        yield _installed.LIBRARY
    except ImportError:
        pass
    root = os.path.dirname(os.path.dirname(here))  # a checkout: python/btdftab
    for b in ("build", "builddir"):
        yield os.path.join(root, b, "libbtdf.so")
    found = ctypes.util.find_library("btdf")
    if found:
        yield found


_lib = None
_lib_path = None


def _library():
    global _lib, _lib_path
    if _lib is not None:
        return _lib
    tried = []
    for path in _candidates():
        if os.path.sep in path and not os.path.exists(path):
            tried.append(path + " (absent)")
            continue
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
            continue
        _declare(lib)
        _lib, _lib_path = lib, path
        return lib
    raise BtdfError("libbtdf not found; tried: %s. Install the package (pip install .), "
                    "build the project (meson compile -C build) or set BTDFTAB_LIBRARY"
                    % ("; ".join(tried) or "nothing"))


def _declare(lib):
    d, i, sz, vp, cp = (ctypes.c_double, ctypes.c_int, ctypes.c_size_t, ctypes.c_void_p,
                        ctypes.c_char_p)
    dp, pp = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(_Params)

    def f(name, res, *args):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, list(args)

    f("btdf_version_string", cp)
    f("btdf_strerror", cp, i)
    f("btdf_params_check", i, pp, cp, sz)
    f("btdf_eval_batch", i, pp, sz, dp, dp, dp, dp, ctypes.POINTER(sz))
    for name in ("btdf_rho_deg", "btdf_rho_r_deg", "btdf_rho_r"):
        f(name, d, d, d, d, d, d, d)
    f("btdf_fresnel_t", d, d, d)
    f("btdf_fresnel_r", d, d, d)
    f("btdf_transmittance", i, pp, d, dp)
    f("btdf_reflectance", i, pp, d, dp)
    f("btdf_eval_r", i, pp, d, d, d, dp)
    f("btdf_table_read", i, cp, ctypes.POINTER(vp), cp, sz)
    f("btdf_table_write", i, vp, cp, vp, cp, sz)
    f("btdf_table_free", None, vp)
    f("btdf_table_get_kind", i, vp)
    f("btdf_table_get_rule", i, vp)
    f("btdf_table_get_params", pp, vp)
    f("btdf_table_slice_count", sz, vp)
    f("btdf_table_node_count", sz, vp)
    f("btdf_table_slice", i, vp, sz, ctypes.POINTER(_Slice))
    f("btdf_table_eval", i, vp, d, d, d, dp)
    f("btdf_table_part", vp, vp, i)
    f("btdf_table_parts", i, vp)
    f("btdf_table_opts_default", None, ctypes.POINTER(_TableOpts))
    f("btdf_table_build", i, ctypes.POINTER(_TableOpts), ctypes.POINTER(vp), cp, sz)
    f("btdf_scatfun_read", i, cp, ctypes.POINTER(vp), cp, sz)
    f("btdf_scatfun_free", None, vp)
    f("btdf_scatfun_eval_side", i, vp, i, i, d, d, d, dp)
    f("btdf_scatfun_channels", i, vp)
    f("btdf_scatfun_eta", d, vp)
    f("btdf_scatfun_sides", i, vp)
    f("btdf_scatfun_build", i, pp, d, i, i, ctypes.POINTER(vp), cp, sz)
    f("btdf_scatfun_write", i, vp, cp, cp, cp, sz)
    for name in ("btdf_rho_model_deg", "btdf_rho_r_model_deg"):
        f(name, d, i, d, d, d, d, d, d)
    fo = ctypes.POINTER(_FullOpts)
    f("btdf_full_opts_default", None, fo)
    f("btdf_full_new", i, d, d, fo, ctypes.POINTER(vp), cp, sz)
    f("btdf_full_free", None, vp)
    for name in ("btdf_full_rho", "btdf_full_rho_deg", "btdf_full_rho_r",
                 "btdf_full_rho_r_deg"):
        f(name, d, vp, d, d, d)
    f("btdf_full_albedo", i, vp, d, ctypes.POINTER(_FullAlbedos))
    f("btdf_full_info", None, vp, ctypes.POINTER(_FullStats))
    if hasattr(lib, "btdf_full_get_series"):  # libbtdf 0.4 from this release on
        f("btdf_full_get_series", i, vp, ctypes.POINTER(_FullSeries))
    if hasattr(lib, "btdf_table_get_full"):  # from this release on
        f("btdf_table_get_full", vp, vp, i)


def _check(status, what, msg=None):
    if status != 0:
        reason = msg.value.decode("utf-8", "replace") if msg is not None else ""
        raise BtdfError("%s: %s%s" % (what, _library().btdf_strerror(status).decode(),
                                      (": " + reason) if reason else ""))


def version():
    """The library's version string."""
    return _library().btdf_version_string().decode()


def library_path():
    """The path of the libbtdf this module loaded."""
    _library()
    return _lib_path


def _model_id(model):
    if model not in _MODEL_IDS:
        raise ValueError("model %r: one of %s" % (model, ", ".join(MODELS)))
    return _MODEL_IDS[model]


def _params(n, s, k0, model=0):
    """A checked single-channel btdf_params; model full is checked as smith (it has
    smith's parameters; its tally is made by Full)."""
    p = _Params()
    p.channels = 1
    p.ior[0] = float(n)
    p.smoothness = float(s)
    p.k0 = float(k0)
    p.model = 1 if model == 2 else model
    msg = ctypes.create_string_buffer(256)
    if _library().btdf_params_check(ctypes.byref(p), msg, 256) != 0:
        raise ValueError("model parameters: " + msg.value.decode("utf-8", "replace"))
    p.model = model
    return p


def _f64(*xs):
    """The arguments as float64 arrays broadcast to one shape (contiguous)."""
    arrs = np.broadcast_arrays(*[np.asarray(x, dtype=np.float64) for x in xs])
    return [np.array(a, dtype=np.float64, order="C") for a in arrs]  # 0-d stays 0-d


def _groups(n, s, k0, model=0):
    """(params, index array) for each distinct (n, s, k0) of the flat arrays."""
    key = np.stack([n, s, k0], axis=-1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    return [(_params(*uniq[g], model=model), np.nonzero(inv == g)[0])
            for g in range(len(uniq))]


def _out(arr, shape):
    a = arr.reshape(shape)
    return a if a.ndim else float(a)


def _dp(a):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def params_check(ior, smoothness, k0=0.7, model="xu-sun"):
    """Checks a material as btdf_params_check does (ior: one index or three); raises
    ValueError naming the value and what is allowed."""
    _ior_params(ior, smoothness, k0, 1 if _model_id(model) == 2 else _model_id(model))


def rho(ior, smoothness, ti, to, phi, k0=0.7, model="xu-sun", paths=None, seed=None):
    """rho of the model (btdf_eval; btdf_full_rho for full), 1/sr, radians: ti in
    [0, pi/2], to in [pi/2, pi], finite phi. Eq. 25 by default."""
    m = _model_id(model)
    n, s, k, a, b, c = _f64(ior, smoothness, k0, ti, to, phi)
    shape = a.shape
    n, s, k, a, b, c = (x.reshape(-1) for x in (n, s, k, a, b, c))
    if m == 2:
        return _full_each("rho", "btdf_full_rho", (n, s, k, a, b, c), shape, paths, seed,
                          _angles_t_rad)
    out = np.empty(a.size)
    lib = _library()
    for p, idx in _groups(n, s, k, m):
        ta, tb, tc = (np.ascontiguousarray(x[idx]) for x in (a, b, c))
        o = np.empty(idx.size)
        bad = ctypes.c_size_t(0)
        st = lib.btdf_eval_batch(ctypes.byref(p), idx.size, _dp(ta), _dp(tb), _dp(tc),
                                 _dp(o), ctypes.byref(bad))
        if st != 0:
            j = bad.value
            if j < idx.size and _angles_t_rad(ta[j], tb[j], tc[j]):
                raise ValueError("rho: %s at flat index %d"
                                 % (_angles_t_rad(ta[j], tb[j], tc[j]), int(idx[j])))
            _check(st, "btdf_eval_batch")
        out[idx] = o
    return _out(out, shape)


def _angles_t_rad(a, b, c):
    return (None if 0 <= a <= np.pi / 2 and np.pi / 2 <= b <= np.pi and np.isfinite(c) else
            "angles (%r, %r, %r): need ti in [0, pi/2], to in [pi/2, pi], finite phi "
            "(radians)" % (a, b, c))


def _angles_t_deg(a, b, c):
    return (None if 0 <= a <= 90 and 90 <= b <= 180 and np.isfinite(c) else
            "angles (%r, %r, %r): need ti in [0, 90], to in [90, 180] degrees, finite phi"
            % (a, b, c))


def _angles_r_rad(a, b, c):
    return (None if 0 <= a <= np.pi / 2 and 0 <= b <= np.pi / 2 and np.isfinite(c) else
            "angles (%r, %r, %r): need ti, tr in [0, pi/2], finite phi (radians)"
            % (a, b, c))


def _angles_r_deg(a, b, c):
    return (None if 0 <= a <= 90 and 0 <= b <= 90 and np.isfinite(c) else
            "angles (%r, %r, %r): need ti, tr in [0, 90] degrees, finite phi" % (a, b, c))


def _scalar(fn, args, check, what):
    """fn over the broadcast arrays, element by element, each element checked."""
    arrs = _f64(*args)
    shape = arrs[0].shape
    flat = [x.reshape(-1) for x in arrs]
    out = np.empty(flat[0].size)
    for j in range(out.size):
        v = [float(x[j]) for x in flat]
        why = check(*v)
        if why:
            raise ValueError("%s: %s at flat index %d" % (what, why, j))
        out[j] = fn(*v)
    return _out(out, shape)


def _param_why(n, s, k0, model=0):
    try:
        _params(n, s, k0, model)
    except ValueError as e:
        return str(e)
    return None


_pcache = {}


def _pc(n, s, k0, model=0):
    """_params' verdict, remembered (the per-element paths call it once per element)."""
    key = (n, s, k0, model)
    if key not in _pcache:
        if len(_pcache) > 4096:
            _pcache.clear()
        _pcache[key] = _param_why(n, s, k0, model)
    return _pcache[key]


_fcache = {}


def _full_of(n, s, paths, seed):
    """The Full object of (n, s, paths, seed), made once (its tally is the cost)."""
    key = (float(n), float(s), int(paths or FULL_PATHS_DEFAULT), int(1 if seed is None
                                                                      else seed))
    f = _fcache.get(key)
    if f is None:
        if len(_fcache) >= 16:
            _fcache.clear()
        f = _fcache[key] = Full(*key)
    return f


def _full_each(what, cname, flat, shape, paths, seed, angle_why):
    """A btdf_full_* evaluation over flat (n, s, k0, a, b, c), element by element."""
    n, s, k, a, b, c = flat
    out = np.empty(a.size)
    for j in range(a.size):
        why = _pc(float(n[j]), float(s[j]), float(k[j]), 2) or angle_why(a[j], b[j], c[j])
        if why:
            raise ValueError("%s: %s at flat index %d" % (what, why, j))
        f = _full_of(n[j], s[j], paths, seed)
        out[j] = getattr(_library(), cname)(f._h, a[j], b[j], c[j])
    return _out(out, shape)


def _model_form(what, cname_full, model_fn, ior, smoothness, k0, ti, to, phi, model, paths,
                seed, angle_why):
    """The degree forms and rho_r: the model's scalar entry, full through Full."""
    m = _model_id(model)
    arrs = _f64(ior, smoothness, k0, ti, to, phi)
    shape = arrs[0].shape
    flat = [x.reshape(-1) for x in arrs]
    if m == 2:
        return _full_each(what, cname_full, flat, shape, paths, seed, angle_why)

    def check(n, s, k0_, a, b, c):
        return _pc(n, s, k0_, m) or angle_why(a, b, c)
    return _scalar(lambda n, s, k0_, a, b, c: model_fn(m, n, s, k0_, a, b, c), arrs, check,
                   what)


def rho_deg(ior, smoothness, ti, to, phi, k0=0.7, model="xu-sun", paths=None, seed=None):
    """rho with the angles in degrees (btdf_rho_model_deg, btdf_full_rho_deg for full):
    what `btdftab eval --model MODEL` prints."""
    return _model_form("rho_deg", "btdf_full_rho_deg", _library().btdf_rho_model_deg, ior,
                       smoothness, k0, ti, to, phi, model, paths, seed, _angles_t_deg)


def _rho_r_rad(m, n, s, k0, a, b, c):
    out1 = (ctypes.c_double * MAX_CHANNELS)()
    _check(_library().btdf_eval_r(ctypes.byref(_params(n, s, k0, m)), a, b, c, out1),
           "btdf_eval_r")
    return out1[0]


def rho_r(ior, smoothness, ti, tr, phi, k0=0.7, model="xu-sun", paths=None, seed=None):
    """The same facets' reflection rho_r (btdf_eval_r, btdf_full_rho_r for full), 1/sr,
    radians: ti, tr in [0, pi/2], phi = pi the specular plane."""
    return _model_form("rho_r", "btdf_full_rho_r", _rho_r_rad, ior, smoothness, k0, ti, tr,
                       phi, model, paths, seed, _angles_r_rad)


def rho_r_deg(ior, smoothness, ti, tr, phi, k0=0.7, model="xu-sun", paths=None, seed=None):
    """rho_r with the angles in degrees (btdf_rho_r_model_deg, btdf_full_rho_r_deg):
    `btdftab eval --part reflection --model MODEL`."""
    return _model_form("rho_r_deg", "btdf_full_rho_r_deg", _library().btdf_rho_r_model_deg,
                       ior, smoothness, k0, ti, tr, phi, model, paths, seed, _angles_r_deg)


def _integral(cname, ior, smoothness, ti, k0, model, paths, seed):
    lib = _library()
    m = _model_id(model)
    fn = getattr(lib, cname)
    out1 = (ctypes.c_double * MAX_CHANNELS)()
    side = "T" if cname == "btdf_transmittance" else "R"

    def one(n, s, k0_, a):
        if m == 2:
            return getattr(_full_of(n, s, paths, seed).albedos(a), side)
        _check(fn(ctypes.byref(_params(n, s, k0_, m)), a, out1), cname)
        return out1[0]

    def check(n, s, k0_, a):
        return _pc(n, s, k0_, m) or (None if 0 <= a <= np.pi / 2 else
                                     "ti %r: need [0, pi/2] (radians)" % a)
    return _scalar(one, (ior, smoothness, k0, ti), check, cname)


def T(ior, smoothness, ti, k0=0.7, model="xu-sun", paths=None, seed=None):
    """Hemispherical transmittance T(ti) (btdf_transmittance; btdf_full_albedo's T for
    full), ti in radians."""
    return _integral("btdf_transmittance", ior, smoothness, ti, k0, model, paths, seed)


def R(ior, smoothness, ti, k0=0.7, model="xu-sun", paths=None, seed=None):
    """Hemispherical reflectance R(ti) of the same facets (btdf_reflectance; full:
    btdf_full_albedo's R)."""
    return _integral("btdf_reflectance", ior, smoothness, ti, k0, model, paths, seed)


def albedo(ior, smoothness, ti, k0=0.7, model="xu-sun", paths=None, seed=None):
    """R(ti) + T(ti): what the surface scatters at all (xu-sun and smith lose the rest to
    the shadowing term; full keeps it, to its tally's noise; `btdftab albedo` prints it
    as R+T)."""
    kw = dict(k0=k0, model=model, paths=paths, seed=seed)
    return np.add(R(ior, smoothness, ti, **kw), T(ior, smoothness, ti, **kw))


class Full:
    """The model full of one material (btdf_full_new): smith's single scattering plus the
    light scattered two or more times, tallied once by a random walk on the Smith
    microsurface (deterministic: the same bits whatever the thread count). Make one per
    material and reuse it; rho etc. with model="full" keep one per material for you."""

    def __init__(self, ior, smoothness, paths=FULL_PATHS_DEFAULT, seed=1, threads=0):
        lib = _library()
        _params(ior, smoothness, 0.7, 2)  # the ranges, with a clear error
        o = _FullOpts()
        lib.btdf_full_opts_default(ctypes.byref(o))
        o.paths, o.seed, o.threads = int(paths), int(seed), int(threads)
        h = ctypes.c_void_p()
        msg = ctypes.create_string_buffer(512)
        st = lib.btdf_full_new(float(ior), float(smoothness), ctypes.byref(o),
                               ctypes.byref(h), msg, 512)
        if st == 1:  # BTDF_EINVAL: a bad value, named in the message
            raise ValueError("Full: " + msg.value.decode("utf-8", "replace"))
        _check(st, "btdf_full_new", msg)
        self._h = h
        self.ior, self.smoothness = float(ior), float(smoothness)
        self.paths, self.seed = int(paths), int(seed)

    def _each(self, cname, ti, to, phi, why):
        a, b, c = _f64(ti, to, phi)
        shape = a.shape
        a, b, c = (x.reshape(-1) for x in (a, b, c))
        fn = getattr(_library(), cname)
        out = np.empty(a.size)
        for j in range(a.size):
            w = why(a[j], b[j], c[j])
            if w:
                raise ValueError("Full: %s at flat index %d" % (w, j))
            out[j] = fn(self._h, a[j], b[j], c[j])
        return _out(out, shape)

    def rho(self, ti, to, phi):
        """rho_full (btdf_full_rho), radians."""
        return self._each("btdf_full_rho", ti, to, phi, _angles_t_rad)

    def rho_deg(self, ti, to, phi):
        return self._each("btdf_full_rho_deg", ti, to, phi, _angles_t_deg)

    def rho_r(self, ti, tr, phi):
        """The reflection of full (btdf_full_rho_r), radians."""
        return self._each("btdf_full_rho_r", ti, tr, phi, _angles_r_rad)

    def rho_r_deg(self, ti, tr, phi):
        return self._each("btdf_full_rho_r_deg", ti, tr, phi, _angles_r_deg)

    def albedos(self, ti):
        """btdf_full_albedo at one ti (radians): an object with T, R (full), T1, R1
        (single scattering), Tms, Rms and their standard errors Tms_se, Rms_se."""
        a = _FullAlbedos()
        if not 0 <= float(ti) <= np.pi / 2:
            raise ValueError("Full.albedos: ti %r: need [0, pi/2] (radians)" % (ti,))
        _check(_library().btdf_full_albedo(self._h, float(ti), ctypes.byref(a)),
               "btdf_full_albedo")
        return a

    def info(self):
        """btdf_full_info: dict of nodes, paths, seconds, lost, order1_gap."""
        st = _FullStats()
        _library().btdf_full_info(self._h, ctypes.byref(st))
        return {k: getattr(st, k) for k, _ in _FullStats._fields_}

    def series(self):
        """btdf_full_get_series: dict of node_deg (nodes,), poly (M, K, K), coef
        (nodes, 2, K, M) and clip (nodes, SUB + 1, 2), the multiply scattered part as
        btdf/btdf.h spells it."""
        lib = _library()
        if not hasattr(lib, "btdf_full_get_series"):
            raise BtdfError("this libbtdf (%s) has no btdf_full_get_series" % version())
        sr = _FullSeries()
        _check(lib.btdf_full_get_series(self._h, ctypes.byref(sr)), "btdf_full_get_series")
        k, m, nn = SERIES_K, SERIES_M, sr.nodes
        return {"node_deg": np.array(sr.node_deg[:nn]),
                "poly": np.array(sr.poly[:]).reshape(m, k, k),
                "coef": np.array(sr.coef[:]).reshape(SERIES_NODES, 2, k, m)[:nn].copy(),
                "clip": np.array(sr.clip[:]).reshape(SERIES_NODES, SERIES_SUB + 1,
                                                     2)[:nn].copy()}

    @classmethod
    def _borrow(cls, handle, owner, ior, smoothness):
        """A tally that another object owns (a full table's): kept alive by holding the
        owner, never freed here."""
        f = cls.__new__(cls)
        f._h, f._owner = handle, owner
        f.ior, f.smoothness = float(ior), float(smoothness)
        f.paths, f.seed = None, None  # the file's tally: its options are not recorded
        return f

    def close(self):
        if getattr(self, "_owner", None) is not None:  # borrowed: the owner frees it
            self._h = None
            return
        if getattr(self, "_h", None):
            _library().btdf_full_free(self._h)
            self._h = None

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: the process frees it anyway
            pass


def fresnel_t(ior, ti):
    """Flat-interface Fresnel transmittance Ft(ti) (btdf_fresnel_t), radians."""
    return _scalar(_library().btdf_fresnel_t, (ior, ti), lambda n, a: None, "fresnel_t")


def fresnel_r(ior, ti):
    """Flat-interface Fresnel reflectance Fr(ti) (btdf_fresnel_r), radians."""
    return _scalar(_library().btdf_fresnel_r, (ior, ti), lambda n, a: None, "fresnel_r")


class Table:
    """A table (.csv, .exr) read by btdf_table_read, or built by build()."""

    def __init__(self, path=None, _handle=None):
        lib = _library()
        if _handle is None:
            h = ctypes.c_void_p()
            msg = ctypes.create_string_buffer(1024)
            _check(lib.btdf_table_read(os.fsencode(path), ctypes.byref(h), msg, 1024),
                   "reading table '%s'" % path, msg)
            _handle = h
        self._h = _handle
        self.path = path
        p = lib.btdf_table_get_params(self._h).contents
        self.channels = p.channels
        self.ior = [p.ior[c] for c in range(p.channels)]
        self.smoothness = p.smoothness
        self.k0 = p.k0
        self.model = MODELS[p.model] if 0 <= p.model < len(MODELS) else str(p.model)
        self.kind = _KINDS.get(lib.btdf_table_get_kind(self._h), "unknown")
        # how facet slices interpolate (btdf_table_rule): rho itself, rho / K or rho / Fr
        self.rule = _RULES.get(lib.btdf_table_get_rule(self._h), "unknown")
        self.parts = {1: "transmission", 2: "reflection", 3: "both"}.get(
            lib.btdf_table_parts(self._h), "unknown")

    def __len__(self):
        """The number of nodes."""
        return _library().btdf_table_node_count(self._h)

    def full(self, channel=0):
        """Model full: the tally of a channel that the table adds to its slices
        (btdf_table_get_full), as a Full that keeps this table alive; None for the other
        models."""
        lib = _library()
        if not hasattr(lib, "btdf_table_get_full"):
            raise BtdfError("this libbtdf (%s) has no btdf_table_get_full" % version())
        if not 0 <= int(channel) < self.channels:
            raise ValueError("channel %r: 0 to %d" % (channel, self.channels - 1))
        h = lib.btdf_table_get_full(self._h, int(channel))
        if not h:
            return None
        return Full._borrow(ctypes.c_void_p(h), self, self.ior[int(channel)],
                            self.smoothness)

    def slices(self):
        """[(ti, rows, cols, values)]: each slice's nodes (values rows x cols x channels)."""
        lib = _library()
        res = []
        for k in range(lib.btdf_table_slice_count(self._h)):
            s = _Slice()
            _check(lib.btdf_table_slice(self._h, k, ctypes.byref(s)), "btdf_table_slice")
            rows = np.ctypeslib.as_array(s.rows, (s.nrows,)).copy()
            cols = np.ctypeslib.as_array(s.cols, (s.ncols,)).copy()
            vals = np.ctypeslib.as_array(s.values, (s.nrows * s.ncols * self.channels,))
            res.append((s.ti, rows, cols,
                        vals.copy().reshape(s.nrows, s.ncols, self.channels)))
        return res

    def eval(self, ti, to, phi, part="transmission"):
        """The table's value (btdf_table_eval) at radians; part "reflection" reads the
        reflection a table holding both parts carries (to is then tr). Shape: the
        broadcast of the angles, with a last axis of 3 for a three-channel table."""
        lib = _library()
        if part not in ("transmission", "reflection"):
            raise ValueError("part %r: transmission or reflection" % (part,))
        h = lib.btdf_table_part(self._h, _PARTS[part])
        if not h:
            raise ValueError("table '%s' holds no %s" % (self.path, part))
        a, b, c = _f64(ti, to, phi)
        shape = a.shape
        a, b, c = (x.reshape(-1) for x in (a, b, c))
        out = np.empty((a.size, self.channels))
        o = (ctypes.c_double * MAX_CHANNELS)()
        for j in range(a.size):
            st = lib.btdf_table_eval(h, a[j], b[j], c[j], o)
            if st != 0:
                raise ValueError("Table.eval: angles (%r, %r, %r) at flat index %d: %s"
                                 % (a[j], b[j], c[j], j, lib.btdf_strerror(st).decode()))
            out[j] = o[:self.channels]
        return _out(out, shape + (3,)) if self.channels == 3 else _out(out[:, 0], shape)

    def write(self, path):
        """Writes the table (.csv or .exr: btdf_table_write; temporary file renamed)."""
        msg = ctypes.create_string_buffer(1024)
        _check(_library().btdf_table_write(self._h, os.fsencode(path), None, msg, 1024),
               "writing '%s'" % path, msg)

    def close(self):
        if getattr(self, "_h", None):
            _library().btdf_table_free(self._h)
            self._h = None

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: the process frees it anyway
            pass


_SIDES = {"enter": 1, "leave": 2, "top": 4, "bottom": 8}


class Bsdf:
    """A SCATFUN .bsdf file (pbrt-v3 "fourier") read by btdf_scatfun_read."""

    def __init__(self, path=None, _handle=None):
        lib = _library()
        if _handle is None:
            h = ctypes.c_void_p()
            msg = ctypes.create_string_buffer(1024)
            _check(lib.btdf_scatfun_read(os.fsencode(path), ctypes.byref(h), msg, 1024),
                   "reading '%s'" % path, msg)
            _handle = h
        self._h = _handle
        self.path = path
        self.channels = lib.btdf_scatfun_channels(self._h)
        self.eta = lib.btdf_scatfun_eta(self._h)

    def eval(self, ti, to, phi, block="enter", adjoint=False):
        """rho read back from the file (btdf_scatfun_eval_side), radians. block:
        "enter" (Eq. 25, index n), "leave" (index 1/n), "top" or "bottom" (rho_r,
        `to` the reflected angle tr); adjoint: pbrt-v3's radiance-mode path."""
        lib = _library()
        if block not in _SIDES:
            raise ValueError("block %r: one of %s" % (block, ", ".join(_SIDES)))
        a, b, c = _f64(ti, to, phi)
        shape = a.shape
        a, b, c = (x.reshape(-1) for x in (a, b, c))
        out = np.empty((a.size, self.channels))
        o = (ctypes.c_double * MAX_CHANNELS)()
        for j in range(a.size):
            st = lib.btdf_scatfun_eval_side(self._h, _SIDES[block], 1 if adjoint else 0,
                                            a[j], b[j], c[j], o)
            if st != 0:
                raise ValueError("Bsdf.eval: angles (%r, %r, %r) at flat index %d: %s"
                                 % (a[j], b[j], c[j], j, lib.btdf_strerror(st).decode()))
            out[j] = o[:self.channels]
        return _out(out, shape + (3,)) if self.channels == 3 else _out(out[:, 0], shape)

    def write(self, path):
        msg = ctypes.create_string_buffer(1024)
        _check(_library().btdf_scatfun_write(self._h, os.fsencode(path), None, msg, 1024),
               "writing '%s'" % path, msg)

    def close(self):
        if getattr(self, "_h", None):
            _library().btdf_scatfun_free(self._h)
            self._h = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def open(path):  # noqa: A001  (the module's reader, as btdftab's --table)
    """A Table (.csv, .exr) or a Bsdf (.bsdf), by the file's extension."""
    return Bsdf(path) if str(path).lower().endswith(".bsdf") else Table(path)


def _ior_params(ior, smoothness, k0, model=0):
    iors = list(np.ravel(np.asarray(ior, dtype=np.float64)))
    if len(iors) not in (1, 3):
        raise ValueError("ior: one value or three (R, G, B), not %d" % len(iors))
    p = _Params()
    p.channels = len(iors)
    for c, v in enumerate(iors):
        p.ior[c] = v
    p.smoothness, p.k0 = float(smoothness), float(k0)
    p.model = 1 if model == 2 else model  # full has smith's parameters (checked as such)
    msg = ctypes.create_string_buffer(256)
    rc = _library().btdf_params_check(ctypes.byref(p), msg, 256)
    p.model = model  # the table builder makes full's tally itself
    if rc != 0:
        raise ValueError("model parameters: " + msg.value.decode("utf-8", "replace"))
    return p


def build(ior, smoothness, k0=0.7, tolerance=1e-3, part="transmission", threads=0,
          ti_range=None, format="table", model="xu-sun"):  # noqa: A002
    """Builds an adaptive table (btdf_table_build, the default of `btdftab tabulate`)
    or, with format="bsdf", a .bsdf file's contents (btdf_scatfun_build, all four
    blocks). ior: one index or three; ti_range: (min, max) radians; model xu-sun,
    smith or full for a table (as `btdftab tabulate --model`; full's tally is made with
    the defaults of `btdftab tabulate --model full` and kept in the table); any of the
    three for a .bsdf (full with one index). Returns a Table or a Bsdf; a budget that stops refinement first raises
    BtdfError."""
    lib = _library()
    p = _ior_params(ior, smoothness, k0, _model_id(model))
    if format == "bsdf" and model == "full" and p.channels == 3:
        raise ValueError("model 'full' with three indices %r: a .bsdf of full holds one index "
                         "(three channels' transmission is read along the reverse path, whose "
                         "tally is another)" % (ior,))
    msg = ctypes.create_string_buffer(1024)
    h = ctypes.c_void_p()
    if format == "bsdf":
        _check(lib.btdf_scatfun_build(ctypes.byref(p), float(tolerance), 15, int(threads),
                                      ctypes.byref(h), msg, 1024), "btdf_scatfun_build", msg)
        return Bsdf(_handle=h)
    if format != "table":
        raise ValueError("format %r: table or bsdf" % (format,))
    if part not in _PARTS:
        raise ValueError("part %r: transmission, reflection or both" % (part,))
    o = _TableOpts()
    lib.btdf_table_opts_default(ctypes.byref(o))
    o.params = p
    o.tolerance = float(tolerance)
    o.threads = int(threads)
    o.part = _PARTS[part]
    if ti_range is not None:
        o.ti_min, o.ti_max = float(ti_range[0]), float(ti_range[1])
    st = lib.btdf_table_build(ctypes.byref(o), ctypes.byref(h), msg, 1024)
    if st != 0:
        if h:
            lib.btdf_table_free(h)
        _check(st, "btdf_table_build", msg)
    return Table(_handle=h)


from .pane import Pane  # noqa: E402  (it uses the helpers above)
