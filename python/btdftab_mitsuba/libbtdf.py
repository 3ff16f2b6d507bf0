# SPDX-License-Identifier: MIT
"""ctypes binding to the parts of libbtdf the Mitsuba plugin and its checks use.

Tables are read by the library's own readers (btdf_table_read) and copied out slice by
slice with btdf_table_slice: the plugin never parses a table file itself.

The library is looked for, in order: the file named by the environment variable
BTDFTAB_LIBRARY; the path recorded when Meson installed this module; a build folder of
the checkout this module sits in (build/libbtdf.so); the system's library search.
"""
import array
import ctypes
import ctypes.util
import os

KIND_FACET = 0
KIND_GRID = 1
KIND_FACET_RECIPROCAL = 2
KIND_NAMES = {KIND_FACET: "facet", KIND_GRID: "grid",
              KIND_FACET_RECIPROCAL: "facet-reciprocal"}
MAX_CHANNELS = 3
# How facet slices interpolate (btdf/btdf.h, btdf_table_rule): rho itself, or rho / K.
RULE_PLAIN = 0
RULE_CHI = 1


class BtdfError(RuntimeError):
    """A libbtdf call failed; the message names the call, the status and the reason."""


class _Params(ctypes.Structure):
    _fields_ = [("channels", ctypes.c_int),
                ("ior", ctypes.c_double * MAX_CHANNELS),
                ("smoothness", ctypes.c_double),
                ("k0", ctypes.c_double),
                ("model", ctypes.c_int)]  # btdf_model: 0 = xu-sun (ctypes zero-fills)


class _Slice(ctypes.Structure):
    _fields_ = [("ti", ctypes.c_double),
                ("nrows", ctypes.c_size_t),
                ("ncols", ctypes.c_size_t),
                ("rows", ctypes.POINTER(ctypes.c_double)),
                ("cols", ctypes.POINTER(ctypes.c_double)),
                ("values", ctypes.POINTER(ctypes.c_double))]


def _candidates():
    env = os.environ.get("BTDFTAB_LIBRARY")
    if env:
        yield env
        return  # an explicit choice is not second-guessed
    try:
        from . import _installed  # written by meson install
        yield _installed.LIBRARY
    except ImportError:
        pass
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(os.path.dirname(here))
    for b in ("build", "builddir"):
        yield os.path.join(root, b, "libbtdf.so")
    found = ctypes.util.find_library("btdf")
    if found:
        yield found


_lib = None


def library():
    """The loaded libbtdf (ctypes.CDLL), loaded on first use."""
    global _lib
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
        _lib = lib
        return lib
    raise BtdfError("libbtdf not found; tried: %s. Build the project (meson compile -C "
                    "build) or set BTDFTAB_LIBRARY to the library's path"
                    % ("; ".join(tried) or "nothing"))


def _declare(lib):
    dp = ctypes.POINTER(ctypes.c_double)
    tp = ctypes.c_void_p
    lib.btdf_version_string.restype = ctypes.c_char_p
    lib.btdf_strerror.restype = ctypes.c_char_p
    lib.btdf_strerror.argtypes = [ctypes.c_int]
    lib.btdf_table_read.restype = ctypes.c_int
    lib.btdf_table_read.argtypes = [ctypes.c_char_p, ctypes.POINTER(tp), ctypes.c_char_p,
                                    ctypes.c_size_t]
    lib.btdf_table_free.restype = None
    lib.btdf_table_free.argtypes = [tp]
    lib.btdf_table_get_kind.restype = ctypes.c_int
    lib.btdf_table_get_kind.argtypes = [tp]
    lib.btdf_table_get_rule.restype = ctypes.c_int
    lib.btdf_table_get_rule.argtypes = [tp]
    lib.btdf_table_get_params.restype = ctypes.POINTER(_Params)
    lib.btdf_table_get_params.argtypes = [tp]
    lib.btdf_table_slice_count.restype = ctypes.c_size_t
    lib.btdf_table_slice_count.argtypes = [tp]
    lib.btdf_table_slice.restype = ctypes.c_int
    lib.btdf_table_slice.argtypes = [tp, ctypes.c_size_t, ctypes.POINTER(_Slice)]
    lib.btdf_table_eval.restype = ctypes.c_int
    lib.btdf_table_eval.argtypes = [tp, ctypes.c_double, ctypes.c_double, ctypes.c_double, dp]
    lib.btdf_params_check.restype = ctypes.c_int
    lib.btdf_params_check.argtypes = [ctypes.POINTER(_Params), ctypes.c_char_p,
                                      ctypes.c_size_t]
    lib.btdf_eval.restype = ctypes.c_int
    lib.btdf_eval.argtypes = [ctypes.POINTER(_Params), ctypes.c_double, ctypes.c_double,
                              ctypes.c_double, dp]
    lib.btdf_transmittance.restype = ctypes.c_int
    lib.btdf_transmittance.argtypes = [ctypes.POINTER(_Params), ctypes.c_double, dp]
    lib.btdf_eval_r.restype = ctypes.c_int
    lib.btdf_eval_r.argtypes = [ctypes.POINTER(_Params), ctypes.c_double, ctypes.c_double,
                                ctypes.c_double, dp]
    lib.btdf_reflectance.restype = ctypes.c_int
    lib.btdf_reflectance.argtypes = [ctypes.POINTER(_Params), ctypes.c_double, dp]


def _check(status, what, msg=None):
    if status != 0:
        lib = library()
        reason = msg.value.decode("utf-8", "replace") if msg is not None else ""
        raise BtdfError("%s: %s%s" % (what, lib.btdf_strerror(status).decode(),
                                      (": " + reason) if reason else ""))


def make_params(ior, smoothness, k0=0.7):
    """A checked btdf_params: ior is one number or a sequence of 1 or 3."""
    iors = list(ior) if isinstance(ior, (list, tuple)) else [ior]
    p = _Params()
    p.channels = len(iors)
    for c, v in enumerate(iors[:MAX_CHANNELS]):
        p.ior[c] = float(v)
    p.smoothness = float(smoothness)
    p.k0 = float(k0)
    msg = ctypes.create_string_buffer(256)
    _check(library().btdf_params_check(ctypes.byref(p), msg, 256), "model parameters", msg)
    return p


class Table:
    """A table read by btdf_table_read. Keeps the C table for btdf_table_eval (the
    checks compare against it) and exposes its slices as flat double arrays."""

    def __init__(self, path):
        lib = library()
        h = ctypes.c_void_p()
        msg = ctypes.create_string_buffer(512)
        _check(lib.btdf_table_read(os.fsencode(path), ctypes.byref(h), msg, 512),
               "reading table '%s'" % path, msg)
        self._h = h
        self.path = path
        self.kind = lib.btdf_table_get_kind(h)
        self.rule = lib.btdf_table_get_rule(h)
        p = lib.btdf_table_get_params(h).contents
        self.channels = p.channels
        self.ior = [p.ior[c] for c in range(p.channels)]
        self.smoothness = p.smoothness
        self.k0 = p.k0
        self.params = make_params(self.ior, self.smoothness, self.k0)
        count = lib.btdf_table_slice_count(h)
        self.ti = array.array("d")
        self.nrows, self.ncols = array.array("I"), array.array("I")
        self.row_off, self.col_off, self.val_off = (array.array("I"), array.array("I"),
                                                    array.array("I"))
        self.rows, self.cols, self.values = (array.array("d"), array.array("d"),
                                             array.array("d"))
        for k in range(count):
            s = _Slice()
            _check(lib.btdf_table_slice(h, k, ctypes.byref(s)), "slice %d of '%s'" % (k, path))
            self.ti.append(s.ti)
            self.nrows.append(s.nrows)
            self.ncols.append(s.ncols)
            self.row_off.append(len(self.rows))
            self.col_off.append(len(self.cols))
            self.val_off.append(len(self.values))
            self.rows.extend(s.rows[:s.nrows])
            self.cols.extend(s.cols[:s.ncols])
            self.values.extend(s.values[:s.nrows * s.ncols * self.channels])
        if count == 0:
            raise BtdfError("table '%s' has no slices" % path)
        if len(self.values) >= 2 ** 32:
            raise BtdfError("table '%s': %d values, more than 32-bit indices address"
                            % (path, len(self.values)))

    @property
    def kind_name(self):
        return KIND_NAMES.get(self.kind, str(self.kind))

    def eval(self, ti, to, phi):
        """btdf_table_eval: rho~ per channel, angles in radians."""
        out = (ctypes.c_double * MAX_CHANNELS)()
        _check(library().btdf_table_eval(self._h, ti, to, phi, out), "btdf_table_eval")
        return [out[c] for c in range(self.channels)]

    def close(self):
        if self._h:
            library().btdf_table_free(self._h)
            self._h = None

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: the process frees it anyway
            pass


def rho(params, ti, to, phi):
    """btdf_eval: Eq. 25 per channel."""
    out = (ctypes.c_double * MAX_CHANNELS)()
    _check(library().btdf_eval(ctypes.byref(params), ti, to, phi, out), "btdf_eval")
    return [out[c] for c in range(params.channels)]


def transmittance(params, ti):
    """btdf_transmittance: T(ti) per channel."""
    out = (ctypes.c_double * MAX_CHANNELS)()
    _check(library().btdf_transmittance(ctypes.byref(params), ti, out), "btdf_transmittance")
    return [out[c] for c in range(params.channels)]


def rho_r(params, ti, tr, phi):
    """btdf_eval_r: the reflection rho_r per channel (MODEL.md section 8)."""
    out = (ctypes.c_double * MAX_CHANNELS)()
    _check(library().btdf_eval_r(ctypes.byref(params), ti, tr, phi, out), "btdf_eval_r")
    return [out[c] for c in range(params.channels)]


def reflectance(params, ti):
    """btdf_reflectance: R(ti) per channel."""
    out = (ctypes.c_double * MAX_CHANNELS)()
    _check(library().btdf_reflectance(ctypes.byref(params), ti, out), "btdf_reflectance")
    return [out[c] for c in range(params.channels)]
