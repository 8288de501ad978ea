"""A native binding that calls a compiled CasADi function on NumPy arrays with no Python in between.

CasADi's generated C exports ``int f(const double** arg, double** res, long long* iw, double* w,
int mem)``.  :func:`binding` returns a :class:`Caller` for such a function: a small CPython
extension type (the C source is :data:`SOURCE`, built once per machine with the system C compiler
against this interpreter's and NumPy's headers and cached under the hash of the source,
compiler, flags, Python and NumPy versions) that, in one C call,

* checks every argument is an exact ``numpy.ndarray`` of float64, native byte order, aligned,
  C-contiguous and of its input's shape ``(size,)``, and returns ``None`` otherwise (the caller
  then takes its general path, which converts, validates and names the argument);
* points the function's argument array at the NumPy data (no copy), allocates the output array
  and points the result array at it, and calls the function;
* returns the output: shape ``(rows,)`` (``kind`` 0), ``(rows, cols)`` in Fortran order, the
  column-major layout CasADi writes (``kind`` 1), or a float (``kind`` 2); a sparse output is
  scattered into a dense one.

The call holds the GIL from start to end (it never runs Python code between setting the argument
pointers and returning), so its preallocated pointer and work arrays are never used by two threads
at once.  A free-threaded interpreter (``Py_GIL_DISABLED``) gets no binding.

When the binding cannot be built (no compiler, no ``Python.h``, a compile error, an unwritable
cache) :func:`binding` returns ``None`` with the reason in :func:`unavailable_reason`, and callers
use CasADi's buffer interface instead, with identical results: both run the same compiled function.
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib.machinery
import importlib.util
import os
import subprocess
import sys
import sysconfig
import tempfile
import threading
from pathlib import Path
from typing import Any

import numpy as np

from designkit.models import codegen

__all__ = ["FLAGS", "SOURCE", "binding", "unavailable_reason"]

_MODULE = "_designkit_one_state"

FLAGS: tuple[str, ...] = ("-O2", "-fPIC", "-shared")
"""Compiler flags of the extension (it only moves pointers: the model's arithmetic is in the function's library)."""

SOURCE = r"""
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <string.h>

#define DK_MAX_IN 16
typedef int (*dk_fn)(const double **arg, double **res, long long *iw, double *w, int mem);

typedef struct {
    PyObject_HEAD
    dk_fn fn;
    Py_ssize_t n_in;            /* inputs of the function, p included */
    int shared;                 /* 1: the last input is p; 0: the last argument must be None */
    npy_intp sizes[DK_MAX_IN];
    int kind;                   /* 0 vector (rows,), 1 matrix (rows, cols) Fortran order, 2 scalar */
    npy_intp rows, cols, nnz;
    npy_intp *flat;             /* column-major index of each nonzero of a sparse output, else NULL */
    const double **arg;
    double **res;
    long long *iw;
    double *w;
    double *scratch;            /* the nonzeros of a sparse or scalar output */
    PyObject *keep;             /* kept alive: the loaded library */
} Caller;

static void Caller_dealloc(Caller *self) {
    PyMem_Free(self->flat); PyMem_Free(self->arg); PyMem_Free(self->res);
    PyMem_Free(self->iw); PyMem_Free(self->w); PyMem_Free(self->scratch);
    Py_XDECREF(self->keep);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *Caller_call(Caller *self, PyObject *args, PyObject *kwds) {
    Py_ssize_t n = PyTuple_GET_SIZE(args), given, k;
    if ((kwds && PyDict_GET_SIZE(kwds)) || n != self->n_in + (self->shared ? 0 : 1)) {
        PyErr_SetString(PyExc_TypeError, "Caller: the function's inputs, then p (None without shared inputs)");
        return NULL;
    }
    if (self->shared) {
        if (PyTuple_GET_ITEM(args, n - 1) == Py_None) Py_RETURN_NONE;
        given = n;
    } else {
        if (PyTuple_GET_ITEM(args, n - 1) != Py_None) Py_RETURN_NONE;
        given = n - 1;
    }
    for (k = 0; k < given; ++k) {  /* checks only: nothing is allocated or written before the output */
        PyObject *a = PyTuple_GET_ITEM(args, k);
        PyArrayObject *x;
        if (!PyArray_CheckExact(a)) Py_RETURN_NONE;
        x = (PyArrayObject *)a;
        if (PyArray_NDIM(x) != 1 || PyArray_DIM(x, 0) != self->sizes[k] || PyArray_TYPE(x) != NPY_DOUBLE
            || !PyArray_ISCARRAY_RO(x) || !PyArray_ISNOTSWAPPED(x)) Py_RETURN_NONE;
    }
    PyObject *out = NULL;
    double *dst = NULL;
    if (self->kind == 0) {
        out = PyArray_SimpleNew(1, &self->rows, NPY_DOUBLE);
    } else if (self->kind == 1) {
        npy_intp dims[2] = {self->rows, self->cols};
        out = PyArray_New(&PyArray_Type, 2, dims, NPY_DOUBLE, NULL, NULL, 0, NPY_ARRAY_F_CONTIGUOUS, NULL);
    }
    if (self->kind != 2) {
        if (out == NULL) return NULL;
        dst = (double *)PyArray_DATA((PyArrayObject *)out);
    }
    /* From here to the return no Python code runs: the shared pointer and work arrays are ours. */
    for (k = 0; k < given; ++k) self->arg[k] = (const double *)PyArray_DATA((PyArrayObject *)PyTuple_GET_ITEM(args, k));
    self->res[0] = (self->flat != NULL || self->kind == 2) ? self->scratch : dst;
    int rc = self->fn(self->arg, self->res, self->iw, self->w, 0);
    if (rc != 0) {
        Py_XDECREF(out);
        PyErr_Format(PyExc_RuntimeError, "evaluation of the compiled function failed (return code %d)", rc);
        return NULL;
    }
    if (self->kind == 2) return PyFloat_FromDouble(self->nnz > 0 ? self->scratch[0] : 0.0);
    if (self->flat != NULL) {
        memset(dst, 0, sizeof(double) * self->rows * self->cols);
        for (k = 0; k < self->nnz; ++k) dst[self->flat[k]] = self->scratch[k];
    }
    return out;
}

static PyTypeObject CallerType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "_designkit_one_state.Caller",
    .tp_basicsize = sizeof(Caller),
    .tp_dealloc = (destructor)Caller_dealloc,
    .tp_call = (ternaryfunc)Caller_call,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A compiled CasADi function called on NumPy arrays (designkit.models.native).",
};

static void *dk_calloc(Py_ssize_t count, size_t size) { return PyMem_Calloc(count > 0 ? count : 1, size); }

/* make(address, sizes, shared, kind, rows, cols, flat, sz_arg, sz_res, sz_iw, sz_w, keep) */
static PyObject *make(PyObject *module, PyObject *args) {
    unsigned long long address;
    PyObject *sizes, *flat, *keep;
    int shared, kind;
    Py_ssize_t rows, cols, sz_arg, sz_res, sz_iw, sz_w, k;
    if (!PyArg_ParseTuple(args, "KO!iinnOnnnnO", &address, &PyTuple_Type, &sizes, &shared, &kind, &rows, &cols,
                          &flat, &sz_arg, &sz_res, &sz_iw, &sz_w, &keep)) return NULL;
    Py_ssize_t n_in = PyTuple_GET_SIZE(sizes);
    if (flat != Py_None && !PyTuple_Check(flat)) {
        PyErr_SetString(PyExc_ValueError, "make: flat must be a tuple or None");
        return NULL;
    }
    if (n_in < 1 || n_in > DK_MAX_IN || sz_arg < n_in || sz_res < 1 || kind < 0 || kind > 2) {
        PyErr_SetString(PyExc_ValueError, "make: unsupported function layout");
        return NULL;
    }
    Caller *self = PyObject_New(Caller, &CallerType);
    if (self == NULL) return NULL;
    self->flat = NULL; self->arg = NULL; self->res = NULL; self->iw = NULL; self->w = NULL; self->scratch = NULL;
    self->fn = (dk_fn)(uintptr_t)address;
    self->n_in = n_in; self->shared = shared; self->kind = kind; self->rows = rows; self->cols = cols;
    Py_INCREF(keep); self->keep = keep;
    for (k = 0; k < n_in; ++k) self->sizes[k] = PyLong_AsSsize_t(PyTuple_GET_ITEM(sizes, k));
    self->nnz = (flat == Py_None) ? rows * cols : PyTuple_GET_SIZE(flat);
    self->arg = dk_calloc(sz_arg, sizeof(double *));
    self->res = dk_calloc(sz_res, sizeof(double *));
    self->iw = dk_calloc(sz_iw, sizeof(long long));
    self->w = dk_calloc(sz_w, sizeof(double));
    self->scratch = dk_calloc(self->nnz, sizeof(double));
    if (flat != Py_None) {
        self->flat = dk_calloc(self->nnz, sizeof(npy_intp));
        if (self->flat != NULL)
            for (k = 0; k < self->nnz; ++k) self->flat[k] = PyLong_AsSsize_t(PyTuple_GET_ITEM(flat, k));
    }
    if (!self->arg || !self->res || !self->iw || !self->w || !self->scratch || (flat != Py_None && !self->flat)) {
        Py_DECREF(self);
        return PyErr_NoMemory();
    }
    if (PyErr_Occurred()) { Py_DECREF(self); return NULL; }
    return (PyObject *)self;
}

static PyMethodDef methods[] = {{"make", make, METH_VARARGS, "Build a Caller."}, {NULL, NULL, 0, NULL}};
static struct PyModuleDef moduledef = {PyModuleDef_HEAD_INIT, "_designkit_one_state", NULL, -1, methods};

PyMODINIT_FUNC PyInit__designkit_one_state(void) {
    import_array();
    if (PyType_Ready(&CallerType) < 0) return NULL;
    PyObject *m = PyModule_Create(&moduledef);
    if (m == NULL) return NULL;
    Py_INCREF(&CallerType);
    if (PyModule_AddObject(m, "Caller", (PyObject *)&CallerType) < 0) {
        Py_DECREF(&CallerType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
"""
"""C source of the extension module ``_designkit_one_state`` (type ``Caller``, function ``make``)."""

_lock = threading.Lock()
_state: dict[str, Any] = {}


def unavailable_reason() -> str | None:
    """Why the binding cannot be used in this process (None when it can, or before the first attempt)."""
    return _state.get("reason")


def _build() -> Any:
    """The extension module, built (once per machine) and loaded (once per process); sets the reason on failure."""
    if sysconfig.get_config_var("Py_GIL_DISABLED"):
        raise OSError("a free-threaded interpreter: the binding relies on the GIL")
    cc = codegen.find_compiler()
    if cc is None:
        raise OSError("no C compiler on PATH")
    includes = [sysconfig.get_paths()["include"], np.get_include()]
    flags = [*FLAGS, *(["-undefined", "dynamic_lookup"] if sys.platform == "darwin" else [])]
    key = "\0".join([SOURCE, cc, *flags, *includes, sys.version, np.__version__])
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    from designkit.cache import cache_dir

    folder = cache_dir("native")
    library = folder / f"{_MODULE}_{digest}.so"
    if not library.exists():
        folder.mkdir(parents=True, exist_ok=True)
        c_file = folder / f"{_MODULE}_{digest}.c"
        c_file.write_text(SOURCE)
        fd, tmp = tempfile.mkstemp(suffix=".so", dir=folder)
        os.close(fd)
        proc = subprocess.run([cc, *flags, *(f"-I{d}" for d in includes), str(c_file), "-o", tmp],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            os.unlink(tmp)
            first = (proc.stderr.strip().splitlines() or ["unknown error"])[0]
            raise OSError(f"compilation failed ({cc}): {first}")
        os.replace(tmp, library)
    loader = importlib.machinery.ExtensionFileLoader(_MODULE, str(library))
    spec = importlib.util.spec_from_file_location(_MODULE, library, loader=loader)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    loader.exec_module(module)
    return module


def _module() -> Any:
    """The loaded extension module, or None (with :func:`unavailable_reason`)."""
    with _lock:
        if "module" not in _state:
            try:
                _state["module"] = _build()
            except (OSError, ImportError) as exc:
                _state["module"] = None
                _state["reason"] = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return _state["module"]


def binding(library: Path, name: str, sizes: tuple[int, ...], shared: int, kind: int, rows: int, cols: int,
            flat: np.ndarray | None) -> Any:
    """A :class:`Caller` of the exported function ``name`` of the CasADi-generated ``library``, or None.

    Parameters
    ----------
    library : pathlib.Path
        A shared library written by :func:`designkit.models.codegen.compile_function`.
    name : str
        The function's name (its exported symbol).
    sizes : tuple of int
        Length of each (dense column-vector) input, ``p`` included.
    shared : int
        1 when the last input is ``p`` (then required), else 0 (the call's last argument must be None).
    kind : int
        0 vector ``(rows,)``, 1 matrix ``(rows, cols)``, 2 scalar (a float).
    rows, cols : int
        Shape of output 0 (only output 0 is computed).
    flat : numpy.ndarray or None
        Column-major index of each nonzero of a sparse output 0; None when it is dense.

    Returns
    -------
    Caller or None
        Called as ``caller(*inputs, p)``; None when the binding is unavailable (:func:`unavailable_reason`).
    """
    module = _module()
    if module is None:
        return None
    try:
        lib = ctypes.CDLL(str(library))
        if getattr(lib, f"{name}_casadi_int_size")() != 8 or getattr(lib, f"{name}_casadi_real_size")() != 8:
            return None  # the C type of the signature above
        work = [ctypes.c_longlong() for _ in range(4)]
        getattr(lib, f"{name}_work")(*(ctypes.byref(v) for v in work))
        address = ctypes.cast(getattr(lib, name), ctypes.c_void_p).value
        sz_arg, sz_res, sz_iw, sz_w = (int(v.value) for v in work)
        flat_tuple = None if flat is None else tuple(int(i) for i in flat)
        return module.make(address, tuple(int(s) for s in sizes), shared, kind, rows, cols, flat_tuple,
                           sz_arg, sz_res, sz_iw, sz_w, lib)
    except (OSError, AttributeError, ValueError):  # not a CasADi library, or a layout the binding does not take
        return None
