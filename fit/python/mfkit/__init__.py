"""mfkit: microfacet BRDF/NDF math, lookup tables and their validation, from Python.

A thin layer over the C library (ctypes, no compiler at import): the functions of ``mfkit eval``
evaluated on numpy arrays in C, table files read into numpy and written back, the validation
gates and the LTC fitter.  The same C code as the command line, so the same bits.

    import mfkit
    out = mfkit.eval("ndf", ndf="ggx", alpha_x=0.3, alpha_y=0.3, m_x=0, m_y=0, m_z=cos_grid)
    out["D"]                                  # numpy array of the broadcast shape

    t = mfkit.read_table("out/ltc/ltc_ggx.npy")
    t.data.shape                              # (n_1, n_0, nfields): t.data[i1, i0, f]
    t.axes[0].params, t.axes[0].physical_values, t.fields, t.meta

Functions, option and column names are those of ``mfkit eval`` (docs/cli.md): ``mfkit.functions()``
lists them.  Options are keyword arguments spelled without the dashes (``ndf="ggx"``,
``grid_layout="cell-centres"``; ``lambda`` is a Python keyword: ``lambda_=2.0``); every other
keyword is an input column.  Errors are ``mfkit.Error`` subclasses carrying mfkit's one-line
message.
"""
import ctypes
import math
import numbers
import os
import sys
import threading

import numpy as np

from ._version import __version__

__all__ = ["eval", "functions", "read_table", "write_table", "validate", "fit_ltc", "Table", "Axis",
           "Report", "Check", "FitResult", "Error", "DomainError", "FileError", "FormatError",
           "UnsupportedError", "FitError", "__version__"]


# ---- errors ----------------------------------------------------------------------------------

class Error(Exception):
    """An mfkit error: ``str(e)`` is mfkit's one-line message, ``e.status`` the mf_status name."""

    status = "error"

    def __init__(self, message, status=None):
        super().__init__(message)
        if status is not None:
            self.status = status


class DomainError(Error, ValueError):
    """An argument outside the documented domain (unknown function, bad option, missing column)."""
    status = "domain"


class FileError(Error, OSError):
    """A file could not be read or written."""
    status = "io"


class FormatError(Error, ValueError):
    """A file is malformed or truncated."""
    status = "format"


class UnsupportedError(Error, NotImplementedError):
    """The feature is not in this build (EXR without OpenImageIO, fit_ltc without Ceres)."""
    status = "unsupported"


class FitError(Error, RuntimeError):
    """A fit did not converge or an internal error crossed a bridge."""
    status = "fit"


# mf_status (mf_core.h) -> exception class
_STATUS = {1: DomainError, 2: Error, 3: FileError, 4: FormatError, 5: FitError, 6: UnsupportedError, 7: Error,
           8: FitError}
MF_OK, MF_ERR_DOMAIN, MF_ERR_CHECK_FAILED, MF_ERR_UNSUPPORTED = 0, 1, 7, 6


# ---- the C structures the module reads (mirrors of mf_table.h, mf_table_io.h, mf_check.h, mf_eval.h) --

class _Axis(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char * 32), ("physical", ctypes.c_char * 32), ("size", ctypes.c_int),
                ("lo", ctypes.c_double), ("hi", ctypes.c_double), ("mapping", ctypes.c_int),
                ("physical_min", ctypes.c_double)]


class _Meta(ctypes.Structure):
    _fields_ = [("key", ctypes.c_char * 32), ("value", ctypes.c_char * 160)]


class _Table(ctypes.Structure):
    _fields_ = [("naxes", ctypes.c_int), ("axes", _Axis * 6), ("nfields", ctypes.c_int),
                ("fields", (ctypes.c_char * 32) * 32), ("nmeta", ctypes.c_int), ("meta", _Meta * 16),
                ("data", ctypes.POINTER(ctypes.c_double))]


class _HalfError(ctypes.Structure):
    _fields_ = [("max_abs_error", ctypes.c_double), ("max_rel_error", ctypes.c_double),
                ("worst_rel_index", ctypes.c_size_t), ("overflow_count", ctypes.c_size_t),
                ("underflow_count", ctypes.c_size_t), ("subnormal_count", ctypes.c_size_t),
                ("count", ctypes.c_size_t)]


class _FileInfo(ctypes.Structure):
    _fields_ = [("format", ctypes.c_int), ("half_float", ctypes.c_int), ("has_metadata", ctypes.c_int),
                ("has_half_error", ctypes.c_int), ("half_error", _HalfError), ("dds_fields", ctypes.c_int * 4)]


class _Check(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char * 48), ("what", ctypes.c_char * 160), ("worst", ctypes.c_double),
                ("bound", ctypes.c_double), ("passed", ctypes.c_int), ("cases", ctypes.c_long),
                ("worst_at", ctypes.c_char * 200)]


class _Value(ctypes.Structure):
    _fields_ = [("set", ctypes.c_int), ("i", ctypes.c_long), ("d", ctypes.c_double)]


class _WriteOptions(ctypes.Structure):
    _fields_ = [("format", ctypes.c_int), ("half_float", ctypes.c_int), ("dds_fields", ctypes.c_int * 4),
                ("dds_fields_set", ctypes.c_int), ("prefix", ctypes.c_char_p), ("zstd_level", ctypes.c_int),
                ("dds_legacy", ctypes.c_int)]


class _Option(ctypes.Structure):  # mf_eval_option
    _fields_ = [("name", ctypes.c_char_p), ("metavar", ctypes.c_char_p), ("kind", ctypes.c_int),
                ("choices", ctypes.POINTER(ctypes.c_char_p)), ("lo", ctypes.c_long), ("hi", ctypes.c_long),
                ("multiple", ctypes.c_long), ("dlo", ctypes.c_double), ("dhi", ctypes.c_double),
                ("lo_open", ctypes.c_int), ("default", ctypes.c_char_p), ("help", ctypes.c_char_p),
                ("mask", ctypes.c_uint), ("optional", ctypes.c_int)]


class _BakeResult(ctypes.Structure):  # mfpy_bake_result (mfkit_py_full.c)
    _fields_ = [("status", ctypes.c_int), ("gate_passed", ctypes.c_int), ("exported", ctypes.c_int),
                ("interrupted", ctypes.c_int), ("stage", ctypes.c_int), ("nchecks", ctypes.c_int),
                ("checks", _Check * 16), ("nfiles", ctypes.c_int), ("files", (ctypes.c_char * 4096) * 16),
                ("stem", ctypes.c_char * 96), ("fit_seconds", ctypes.c_double), ("gate_seconds", ctypes.c_double),
                ("export_seconds", ctypes.c_double), ("worst_residual", ctypes.c_double),
                ("not_converged", ctypes.c_int), ("message", ctypes.c_char * 1024)]


_ABI = [ctypes.sizeof(_Table), ctypes.sizeof(_Axis), _Table.data.offset, ctypes.sizeof(_Check),
        ctypes.sizeof(_FileInfo), ctypes.sizeof(_HalfError), ctypes.sizeof(_Value), ctypes.sizeof(_WriteOptions),
        ctypes.sizeof(_Option)]

_P = ctypes.c_void_p
_S = ctypes.c_char_p
_I = ctypes.c_int
_SZ = ctypes.c_size_t
_PD = ctypes.POINTER(ctypes.c_double)
_PROGRESS = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_int)
_VALIDATE_PROGRESS = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.POINTER(_Check))

_SIGNATURES = {
    "mfpy_abi": (_I, [ctypes.POINTER(_SZ), _I]),
    "mf_status_str": (_S, [_I]),
    "mf_eval_option_at": (ctypes.POINTER(_Option), [_I]),
    "mf_eval_option_find": (_I, [_S]),
    "mf_eval_option_parse": (_I, [_I, _S, ctypes.POINTER(_Value), ctypes.c_char_p, _SZ]),
    "mf_eval_function_count": (_I, []),
    "mf_eval_function_at": (_P, [_I]),
    "mf_eval_function_find": (_P, [_S]),
    "mf_eval_function_name": (_S, [_P]),
    "mf_eval_function_summary": (_S, [_P]),
    "mf_eval_function_takes": (_I, [_P, _I]),
    "mf_eval_function_requires": (_I, [_P, _I]),
    "mf_eval_function_polygon": (_I, [_P]),
    "mf_eval_check_options": (_I, [_P, ctypes.POINTER(_Value), ctypes.c_char_p, _SZ]),
    "mf_eval_inputs": (_I, [_P, ctypes.POINTER(_Value), ctypes.POINTER(_S), ctypes.POINTER(_I)]),
    "mf_eval_outputs": (_I, [_P, ctypes.POINTER(_Value), ctypes.POINTER(_S)]),
    "mf_eval_run_function": (_I, [_P, ctypes.POINTER(_Value), _I, ctypes.POINTER(_S), ctypes.POINTER(_PD), _SZ,
                                  ctypes.POINTER(_PD), ctypes.c_char_p, _SZ]),
    "mfpy_table_read": (_I, [_S, ctypes.POINTER(_Table), ctypes.POINTER(_FileInfo), ctypes.c_char_p, _SZ]),
    "mf_table_write": (_I, [_S, ctypes.POINTER(_Table), ctypes.POINTER(_WriteOptions), ctypes.POINTER(_HalfError),
                            ctypes.c_char_p, _SZ]),
    "mf_table_write_options_default": (None, [ctypes.POINTER(_WriteOptions)]),
    "mf_table_create": (_I, [ctypes.POINTER(_Table), _I, ctypes.POINTER(_Axis), _I, ctypes.POINTER(_S)]),
    "mf_table_free": (None, [ctypes.POINTER(_Table)]),
    "mf_table_set_meta": (_I, [ctypes.POINTER(_Table), _S, _S]),
    "mf_table_format_from_path": (_I, [_S]),
    "mf_table_format_name": (_S, [_I]),
    "mf_table_axis_param": (ctypes.c_double, [ctypes.POINTER(_Axis), _I]),
    "mf_table_axis_physical": (ctypes.c_double, [ctypes.POINTER(_Axis), ctypes.c_double]),
    "mf_table_uv_from_param": (ctypes.c_double, [ctypes.POINTER(_Axis), ctypes.c_double]),
    "mf_axis_describe": (None, [ctypes.POINTER(_Axis), ctypes.c_char_p, _SZ]),
    "mf_axis_mapping_name": (_S, [_I]),
    "mf_axis_mapping_parse": (_I, [_S, ctypes.POINTER(_I)]),
    "mf_validate_core_count": (_I, []),
    "mf_validate_core": (_I, [ctypes.POINTER(_Check), _I, _VALIDATE_PROGRESS, _P]),
    "mfpy_validate_table": (_I, [ctypes.POINTER(_Table), _I, _S, _I, ctypes.c_uint64, ctypes.POINTER(_Check), _I,
                                 ctypes.POINTER(_I), ctypes.c_char_p, _SZ, ctypes.c_char_p, _SZ]),
}
_FULL_SIGNATURES = {
    "mfpy_full_init": (_I, []),
    "mfpy_bake_result_size": (_SZ, []),
    "mfpy_fit_ltc": (_I, [_S, _I, _I, ctypes.c_uint64, _I, _S, _I, ctypes.POINTER(_I), _PROGRESS,
                          ctypes.POINTER(_BakeResult)]),
}

_HERE = os.path.dirname(os.path.abspath(__file__))


def _load(name, signatures):
    lib = ctypes.CDLL(os.path.join(_HERE, name))
    for fn, (res, args) in signatures.items():
        f = getattr(lib, fn)
        f.restype, f.argtypes = res, args
    sizes = (_SZ * len(_ABI))()
    if lib.mfpy_abi(sizes, len(_ABI)) != len(_ABI) or list(sizes) != _ABI:
        raise ImportError("mfkit: %s does not match this module (structure sizes %s, expected %s): rebuild"
                          % (name, list(sizes), _ABI))
    return lib


_lib = _load("libmfkit_py.so", _SIGNATURES)
_full_lib = None
_full_have = 0
_full_error = None
_full_lock = threading.Lock()


def _full(feature):
    """The second library (fitters, EXR), loaded on first use; UnsupportedError if this build has none."""
    global _full_lib, _full_have, _full_error
    with _full_lock:
        if _full_lib is None and _full_error is None:
            path = os.path.join(_HERE, "libmfkit_py_full.so")
            if not os.path.exists(path):
                _full_error = "this build has neither MFKIT_WITH_CERES nor MFKIT_WITH_OIIO (no libmfkit_py_full.so)"
            else:
                try:
                    sig = dict(_SIGNATURES)
                    sig.update(_FULL_SIGNATURES)
                    _full_lib = _load("libmfkit_py_full.so", sig)
                    _full_have = _full_lib.mfpy_full_init()
                    if _full_lib.mfpy_bake_result_size() != ctypes.sizeof(_BakeResult):
                        _full_lib, _full_error = None, "libmfkit_py_full.so does not match this module: rebuild"
                except OSError as e:
                    _full_error = "libmfkit_py_full.so cannot be loaded: %s" % e
    need = {"exr": 1, "fit": 2}[feature]
    if _full_lib is None or not (_full_have & need):
        what = {"exr": "EXR tables need the OpenImageIO image backend",
                "fit": "fit_ltc needs the fitters (Ceres)"}[feature]
        why = _full_error or ("this build has %s off" % ("MFKIT_WITH_OIIO" if need == 1 else "MFKIT_WITH_CERES"))
        raise UnsupportedError("%s: %s" % (what, why))
    return _full_lib


def _s(b):
    return b.decode("utf-8", "replace") if isinstance(b, bytes) else b


def _raise(status, msg, context=None):
    text = _s(msg.value) if hasattr(msg, "value") else (msg or "")
    if not text:
        text = _s(_lib.mf_status_str(status))
    if context:
        text = "%s: %s" % (context, text)
    raise _STATUS.get(status, Error)(text)


def _enc(s, what):
    if not isinstance(s, str):
        raise DomainError("%s: expected a string, got %s" % (what, type(s).__name__))
    if "\0" in s:
        raise DomainError("%s: contains a NUL character" % what)
    return s.encode("utf-8")


def _path(p, what="path"):
    p = os.fspath(p) if isinstance(p, os.PathLike) else p
    return _enc(p, what)


# ---- eval ------------------------------------------------------------------------------------

def _option_count():
    n = 0  # MF_EVAL_NOPTS: mf_eval_option_at is NULL past the last option
    while _lib.mf_eval_option_at(n):
        n += 1
    return n


_NOPTS = _option_count()


def _options():
    out = []
    for k in range(_NOPTS):
        o = _lib.mf_eval_option_at(k).contents
        choices = []
        if o.choices:
            i = 0
            while o.choices[i]:
                choices.append(_s(o.choices[i]))
                i += 1
        out.append({"name": _s(o.name), "kind": ("enum", "int", "double")[o.kind], "choices": choices or None,
                    "default": _s(o.default), "help": _s(o.help)})
    return out


_OPTION_NAMES = [o["name"] for o in _options()]


def _function(name):
    if not isinstance(name, str):
        raise DomainError("eval: FUNCTION must be a string, got %s" % type(name).__name__)
    f = _lib.mf_eval_function_find(_enc(name, "eval: FUNCTION"))
    if not f:
        raise DomainError("eval: unknown function '%s' (mfkit.functions() lists them)" % name)
    return f


def _columns(f, opts):
    names = (_S * 40)()
    req = (_I * 40)()
    nin = _lib.mf_eval_inputs(f, opts, names, req)
    outs = (_S * 8)()
    nout = _lib.mf_eval_outputs(f, opts, outs)
    return [_s(names[k]) for k in range(nin)], [bool(req[k]) for k in range(nin)], [_s(outs[k]) for k in range(nout)]


def functions():
    """The functions of ``mfkit eval``: a list of dicts (name, summary, options, inputs, required, outputs)."""
    out = []
    for i in range(_lib.mf_eval_function_count()):
        f = _lib.mf_eval_function_at(i)
        inputs, req, outputs = _columns(f, None)
        out.append({"name": _s(_lib.mf_eval_function_name(f)), "summary": _s(_lib.mf_eval_function_summary(f)),
                    "options": [n for k, n in enumerate(_OPTION_NAMES) if _lib.mf_eval_function_takes(f, k)],
                    "inputs": inputs, "required": req, "outputs": outputs})
    return out


def _option_text(name, value):
    if isinstance(value, (bool, np.bool_)):
        raise DomainError("%s: expected a value, got a bool" % name)
    if isinstance(value, str):
        return value
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))  # the shortest text that reads back to the same double
    raise DomainError("%s: expected a string or a number, got %s" % (name, type(value).__name__))


def eval(function, /, **options_and_columns):
    """Evaluates an ``mfkit eval`` function on numpy arrays: ``mfkit.eval("ndf", ndf="ggx", alpha_x=a, ...)``.

    Keyword arguments are the options (ndf, fresnel, g2, points, sided, grid, lambda_ (or
    **{"lambda": L}), grid_layout) and the input columns (arrays or scalars, broadcast against each
    other as numpy does).  Returns a dict {output column: float64 array of the broadcast shape},
    the same values bit for bit as ``mfkit eval`` prints (%.17g reads back exactly).  Rows outside
    the domain give NaN.  Raises DomainError (unknown function, option or column, bad value,
    missing column, shapes that do not broadcast).
    """
    f = _function(function)
    ctx = "eval %s" % function
    opts = (_Value * _NOPTS)()
    msg = ctypes.create_string_buffer(512)
    columns = {}
    for key, value in options_and_columns.items():
        oname = "lambda" if key == "lambda_" else key.replace("_", "-")
        k = _OPTION_NAMES.index(oname) if oname in _OPTION_NAMES else -1
        if k < 0:
            columns[key] = value
            continue
        if opts[k].set:
            raise DomainError("%s: option %s given twice" % (ctx, oname))
        st = _lib.mf_eval_option_parse(k, _enc(_option_text(oname, value), oname), ctypes.byref(opts[k]), msg,
                                       len(msg))
        if st != MF_OK:
            _raise(st, msg, ctx)
    st = _lib.mf_eval_check_options(f, opts, msg, len(msg))
    if st != MF_OK:
        _raise(st, msg, "eval")
    inputs, required, outputs = _columns(f, opts)
    for key in columns:
        if key not in inputs:
            raise DomainError("%s: '%s' is neither an option nor an input column (inputs: %s)"
                              % (ctx, key, ", ".join(n for n, r in zip(inputs, required) if r)))
    for name, req in zip(inputs, required):
        if req and name not in columns:
            raise DomainError("%s: missing required column '%s'" % (ctx, name))
    arrays = []
    for name, value in columns.items():
        try:
            a = np.asarray(value)
            if a.dtype.kind not in "biuf":
                raise TypeError("expected numbers, got dtype %s" % a.dtype)
            arrays.append(a.astype(np.float64, copy=False))
        except (TypeError, ValueError) as e:
            raise DomainError("%s: column '%s': %s" % (ctx, name, e)) from None
    try:
        shape = np.broadcast_shapes(*[a.shape for a in arrays])
    except ValueError:
        raise DomainError("%s: the columns' shapes do not broadcast: %s" % (
            ctx, ", ".join("%s %s" % (n, a.shape) for n, a in zip(columns, arrays)))) from None
    n = math.prod(shape)
    flat = [np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1) for a in arrays]
    outs = [np.empty(n, dtype=np.float64) for _ in outputs]
    c_names = (_S * max(1, len(flat)))(*[_enc(k, "column") for k in columns])
    c_cols = (_PD * max(1, len(flat)))(*[a.ctypes.data_as(_PD) for a in flat])
    c_outs = (_PD * max(1, len(outs)))(*[o.ctypes.data_as(_PD) for o in outs])
    st = _lib.mf_eval_run_function(f, opts, len(flat), c_names, c_cols, n, c_outs, msg, len(msg))
    if st != MF_OK:
        _raise(st, msg, "eval")
    return {name: o.reshape(shape) for name, o in zip(outputs, outs)}


# ---- tables ----------------------------------------------------------------------------------

class Axis:
    """One axis of a table (mf_table_axis of mf_table.h).

    Texel-centre convention: texel i (0 <= i < size) holds the parameter ``params[i]``, lo at the
    first centre and hi at the last (``lo + (hi - lo) i / (size - 1)``), at the texture coordinate
    ``uv[i] = (i + 0.5) / size``; the physical quantity is the mapping of the parameter
    (identity, one_minus_square: 1 - p^2, square: p^2, cos: cos p), clamped to >= physical_min.
    """

    def __init__(self, name, size, lo, hi, mapping="identity", physical=None, physical_min=None):
        self.name, self.size, self.lo, self.hi = str(name), int(size), float(lo), float(hi)
        self.mapping = str(mapping)
        self.physical = str(physical if physical is not None else name)
        self.physical_min = None if physical_min is None or physical_min == -math.inf else float(physical_min)

    def _c(self):
        a = _Axis()
        for field, text in (("name", self.name), ("physical", self.physical)):
            b = _enc(text, "axis " + field)
            if len(b) >= 32:
                raise DomainError("axis %s '%s': longer than 31 bytes" % (field, text))
            setattr(a, field, b)
        m = _I()
        if _lib.mf_axis_mapping_parse(_enc(self.mapping, "axis mapping"), ctypes.byref(m)) != 0:
            raise DomainError("axis %s: unknown mapping '%s' (identity, one_minus_square, square, cos)"
                              % (self.name, self.mapping))
        a.size, a.lo, a.hi, a.mapping = self.size, self.lo, self.hi, m.value
        a.physical_min = -math.inf if self.physical_min is None else self.physical_min
        return a

    @property
    def params(self):
        """The parameter at each texel centre (mf_table_axis_param)."""
        a = self._c()
        return np.array([_lib.mf_table_axis_param(ctypes.byref(a), i) for i in range(self.size)])

    @property
    def physical_values(self):
        """The physical quantity at each texel centre (mapping and clamp)."""
        a = self._c()
        return np.array([_lib.mf_table_axis_physical(ctypes.byref(a), p) for p in self.params])

    @property
    def uv(self):
        """The texture coordinate of each texel centre, (i + 0.5) / size."""
        a = self._c()
        return np.array([_lib.mf_table_uv_from_param(ctypes.byref(a), p) for p in self.params])

    @property
    def description(self):
        a = self._c()
        buf = ctypes.create_string_buffer(512)
        _lib.mf_axis_describe(ctypes.byref(a), buf, len(buf))
        return _s(buf.value)

    def __repr__(self):
        return "Axis(%r, size=%d, lo=%r, hi=%r, mapping=%r, physical=%r, physical_min=%r)" % (
            self.name, self.size, self.lo, self.hi, self.mapping, self.physical, self.physical_min)


class Table:
    """A lookup table: ``data`` of shape (n_{k-1}, ..., n_1, n_0, nfields) (C order, as .npy files:
    ``data[i1, i0, f]`` is field f of texel (i0, i1)), ``axes`` (axis 0 first), ``fields`` (names),
    ``meta`` (dict of the table's key/values), ``info`` (what the file said: format, storage,
    half-float error report; empty for a table made here)."""

    def __init__(self, data, axes, fields, meta=None, info=None):
        self.axes = list(axes)
        self.fields = [str(f) for f in fields]
        self.data = np.asarray(data, dtype=np.float64)
        self.meta = dict(meta or {})
        self.info = dict(info or {})
        shape = tuple(a.size for a in reversed(self.axes)) + (len(self.fields),)
        if self.data.shape != shape:
            raise DomainError("Table: data has shape %s, the axes and fields need %s" % (self.data.shape, shape))

    def field(self, name):
        """The array of one field, shape (n_{k-1}, ..., n_0)."""
        if name not in self.fields:
            raise DomainError("Table: no field '%s' (fields: %s)" % (name, ", ".join(self.fields)))
        return self.data[..., self.fields.index(name)]

    def __repr__(self):
        return "Table(%s, fields=%s, meta=%s)" % (" x ".join("%s[%d]" % (a.name, a.size) for a in self.axes),
                                                  self.fields, self.meta)

    def _c(self):
        """A C mf_table (caller frees with mf_table_free)."""
        if not 1 <= len(self.axes) <= 6:
            raise DomainError("Table: 1 to 6 axes, got %d" % len(self.axes))
        if not 1 <= len(self.fields) <= 32:
            raise DomainError("Table: 1 to 32 fields, got %d" % len(self.fields))
        axes = (_Axis * len(self.axes))(*[a._c() for a in self.axes])
        names = (_S * len(self.fields))(*[_enc(f, "field name") for f in self.fields])
        t = _Table()
        st = _lib.mf_table_create(ctypes.byref(t), len(self.axes), axes, len(self.fields), names)
        if st != MF_OK:
            _raise(st, None, "Table: invalid axes or fields (names 1-31 bytes, sizes >= 1, lo <= hi)")
        try:
            src = np.ascontiguousarray(self.data, dtype=np.float64)
            ctypes.memmove(t.data, src.ctypes.data, src.nbytes)
            for key, value in self.meta.items():
                if _lib.mf_table_set_meta(ctypes.byref(t), _enc(str(key), "meta key"),
                                          _enc(str(value), "meta value")) != MF_OK:
                    raise DomainError("Table: meta '%s': key up to 31 bytes, value up to 159, at most 16 entries"
                                      % key)
        except BaseException:
            _lib.mf_table_free(ctypes.byref(t))
            raise
        return t


def _from_c(t, info):
    axes = []
    for k in range(t.naxes):
        a = t.axes[k]
        axes.append(Axis(_s(a.name), a.size, a.lo, a.hi, _s(_lib.mf_axis_mapping_name(a.mapping)), _s(a.physical),
                         a.physical_min))
    fields = [_s(t.fields[j].value) for j in range(t.nfields)]
    n = t.nfields
    for a in axes:
        n *= a.size
    data = np.ctypeslib.as_array(t.data, shape=(n,)).copy()
    data = data.reshape(tuple(a.size for a in reversed(axes)) + (t.nfields,))
    meta = {_s(t.meta[i].key): _s(t.meta[i].value) for i in range(t.nmeta)}
    return Table(data, axes, fields, meta, info)


def _info_dict(info):
    d = {"format": _s(_lib.mf_table_format_name(info.format)), "storage": "float16" if info.half_float else "float32",
         "has_metadata": bool(info.has_metadata)}
    if info.has_half_error:
        h = info.half_error
        d["half_error"] = {"max_abs_error": h.max_abs_error, "max_rel_error": h.max_rel_error,
                           "overflow_count": h.overflow_count, "underflow_count": h.underflow_count}
    return d


def _lib_for(path):
    return _full("exr") if _lib.mf_table_format_from_path(path) == 1 else _lib  # 1: MF_TABLE_FORMAT_EXR


def _read_c(path):
    p = _path(path)
    lib = _lib_for(p)
    t, info = _Table(), _FileInfo()
    msg = ctypes.create_string_buffer(1024)
    st = lib.mfpy_table_read(p, ctypes.byref(t), ctypes.byref(info), msg, len(msg))
    if st != MF_OK:
        _raise(st, msg)
    return lib, t, info


def read_table(path):
    """Reads a table file of mfkit (.exr, .dds, .json, .npy; .csv in the reference LTC layout) into a Table.

    EXR needs the OpenImageIO backend, in the second library (UnsupportedError without it).
    Files without mfkit metadata read with generic axes (mf_table_io.h).  Raises FileError,
    FormatError, UnsupportedError with mfkit's message ("path: reason").
    """
    lib, t, info = _read_c(path)
    try:
        return _from_c(t, _info_dict(info))
    finally:
        lib.mf_table_free(ctypes.byref(t))


def write_table(path, table, half_float=False, prefix=None, dds_fields=None):
    """Writes a Table to path; the format from the extension (.exr, .dds, .h, .glsl, .hlsl, .json,
    .npy, .csv; mf_table_io.h), atomically.  half_float: EXR/DDS as 16-bit halves.  Returns the
    half-float conversion report (dict) or None."""
    if not isinstance(table, Table):
        raise DomainError("write_table: expected an mfkit.Table, got %s" % type(table).__name__)
    p = _path(path)
    lib = _lib_for(p)
    opt = _WriteOptions()
    _lib.mf_table_write_options_default(ctypes.byref(opt))
    opt.half_float = 1 if half_float else 0
    if prefix is not None:
        opt.prefix = _enc(prefix, "prefix")
    if dds_fields is not None:
        idx = [table.fields.index(f) if isinstance(f, str) and f in table.fields else f for f in dds_fields]
        if len(idx) != 4 or not all(isinstance(i, int) for i in idx):
            raise DomainError("write_table: dds_fields: 4 field names or indices (-1: zeros)")
        opt.dds_fields_set = 1
        for c in range(4):
            opt.dds_fields[c] = idx[c]
    t = table._c()
    half = _HalfError()
    msg = ctypes.create_string_buffer(1024)
    try:
        st = lib.mf_table_write(p, ctypes.byref(t), ctypes.byref(opt), ctypes.byref(half), msg, len(msg))
    finally:
        _lib.mf_table_free(ctypes.byref(t))
    if st != MF_OK:
        _raise(st, msg)
    if not half_float:
        return None
    return {"max_abs_error": half.max_abs_error, "max_rel_error": half.max_rel_error,
            "overflow_count": half.overflow_count, "underflow_count": half.underflow_count,
            "subnormal_count": half.subnormal_count, "count": half.count}


# ---- validation ------------------------------------------------------------------------------

class Check:
    """One check of a report (mf_check): name, what, worst, bound, passed, cases, worst_at."""

    def __init__(self, c):
        self.name, self.what = _s(c.name), _s(c.what)
        self.worst, self.bound, self.passed, self.cases = c.worst, c.bound, bool(c.passed), c.cases
        self.worst_at = _s(c.worst_at)

    def as_dict(self):
        return dict(self.__dict__)

    def __repr__(self):
        return "Check(%s: worst %.4g, bound %.4g, %s)" % (self.name, self.worst, self.bound,
                                                           "pass" if self.passed else "FAIL")


class Report:
    """A gate report: passed, kind (the table's kind, or "core"), checks (list of Check)."""

    def __init__(self, kind, checks):
        self.kind, self.checks = kind, checks
        self.passed = all(c.passed for c in checks)

    def __repr__(self):
        lines = ["%s gate: %s" % (self.kind, "passed" if self.passed else "FAILED")]
        for c in self.checks:
            lines.append("  %-26s %-4s worst %-11.4g bound %-11.4g %s" % (c.name, "pass" if c.passed else "FAIL",
                                                                          c.worst, c.bound, c.worst_at))
        return "\n".join(lines)

    def as_dict(self):
        return {"kind": self.kind, "passed": self.passed, "checks": [c.as_dict() for c in self.checks]}


def _progress_printer(label):
    state = {"last": -1.0}

    def show(done, total, extra=""):
        pct = 100.0 * done / total if total else 100.0
        if done == total or pct - state["last"] >= 1.0:
            state["last"] = pct
            sys.stderr.write("\r%s: %d/%d %s" % (label, done, total, extra) + ("\n" if done == total else ""))
            sys.stderr.flush()
    return show


def validate(table=None, brdf=None, quick=False, seed=1, progress=True):
    """The checks of ``mfkit validate``: without table the property checks of the core math; with a
    table (a path, or a Table) the gate of its kind (the LTC gate with the BRDF ``brdf``, else the
    table's "brdf" metadata, "none" for model-free checks only; with a BRDF also
    ltc_texel_neighbours, every texel against its neighbours' predictions, and where the fitters are
    built, the candidate texels of a table mfkit's fitter made refitted: the same C function as the
    command, so the same report).  Returns a Report; raises on an unreadable file or a table
    of no known kind.  progress: show progress on stderr."""
    if table is None:
        n = _lib.mf_validate_core_count()
        checks = (_Check * n)()
        show = _progress_printer("mfkit validate") if progress else None

        def cb(user, done, total, last):
            if show:
                show(done, total, _s(last.contents.name) if last else "")
        c_cb = _VALIDATE_PROGRESS(cb)
        st = _lib.mf_validate_core(checks, n, c_cb, None)
        if st not in (MF_OK, MF_ERR_CHECK_FAILED):
            _raise(st, None, "validate")
        return Report("core", [Check(checks[i]) for i in range(n)])
    if isinstance(table, Table):
        lib, t, half = _lib, table._c(), 1 if table.info.get("storage") == "float16" else 0
    else:
        lib, t, info = _read_c(table)
        half = info.half_float
    try:  # with the fitters, a table mfkit's fitter made has its candidate texels refitted, as the command does
        lib = _full("fit")
    except UnsupportedError:
        pass
    checks = (_Check * 32)()
    count = _I()
    kind = ctypes.create_string_buffer(64)
    msg = ctypes.create_string_buffer(1024)
    try:
        st = lib.mfpy_validate_table(ctypes.byref(t), half, None if brdf is None else _enc(brdf, "brdf"),
                                     1 if quick else 0, int(seed), checks, 32, ctypes.byref(count), kind, len(kind),
                                     msg, len(msg))
    finally:
        lib.mf_table_free(ctypes.byref(t))
    if st not in (MF_OK, MF_ERR_CHECK_FAILED):
        _raise(st, msg, "validate %s" % (table if not isinstance(table, Table) else "Table"))
    return Report(_s(kind.value), [Check(checks[i]) for i in range(count.value)])


# ---- fitting ---------------------------------------------------------------------------------

class FitResult:
    """The outcome of fit_ltc: passed (the gate), exported, files, checks, report (Report), table
    (the fitted Table read back from its .npy, None when nothing was written), seconds."""

    def __repr__(self):
        return "FitResult(passed=%s, exported=%s, %d files, fit %.1f s, gate %.1f s)" % (
            self.passed, self.exported, len(self.files), self.fit_seconds, self.gate_seconds)


def fit_ltc(brdf="ggx", size=64, samples=4096, seed=1, threads=1, out_dir="out/ltc", force=False, progress=True):
    """Fits an isotropic LTC table to a BRDF, runs the LTC gate and exports every format if it
    passes (``mfkit fit ltc``; mf_ltc_bake).  Needs the fitters (Ceres) in the second library.
    Returns a FitResult; raises DomainError (bad options), FileError, FitError."""
    lib = _full("fit")
    show = _progress_printer("fit ltc %s" % brdf) if progress else None
    lock = threading.Lock()

    def cb(user, done, total):
        if show:
            with lock:
                show(done, total, "texels")
    c_cb = _PROGRESS(cb)
    res = _BakeResult()
    cancel = _I(0)
    for name, v in (("size", size), ("samples", samples), ("threads", threads), ("seed", seed)):
        if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 0:
            raise DomainError("fit_ltc: %s: expected a non-negative integer, got %r" % (name, v))
    st = lib.mfpy_fit_ltc(_enc(brdf, "brdf"), int(size), int(samples), int(seed), int(threads),
                          _path(out_dir, "out_dir"), 1 if force else 0, ctypes.byref(cancel), c_cb, ctypes.byref(res))
    if st not in (MF_OK, MF_ERR_CHECK_FAILED):
        _raise(st, res.message, "fit_ltc")
    r = FitResult()
    r.passed, r.exported = bool(res.gate_passed), bool(res.exported)
    r.files = [_s(res.files[i].value) for i in range(res.nfiles)]
    r.checks = [Check(res.checks[i]) for i in range(res.nchecks)]
    r.report = Report("ltc_isotropic", r.checks)
    r.fit_seconds, r.gate_seconds, r.export_seconds = res.fit_seconds, res.gate_seconds, res.export_seconds
    r.worst_residual, r.not_converged = res.worst_residual, res.not_converged
    npy = [f for f in r.files if f.endswith(".npy")]
    r.table = read_table(npy[0]) if npy else None
    return r
