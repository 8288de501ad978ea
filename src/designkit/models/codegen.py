"""C code generation for CasADi Functions, with a cache and an interpreted fallback.

:func:`compile_function` turns a :class:`casadi.Function` into a shared
library: CasADi's :class:`casadi.CodeGenerator` writes self-contained C, the
system C compiler builds it (``cc -O3 -shared -fPIC``), and
:func:`casadi.external` loads it back as a Function with the same name,
inputs and outputs.  Libraries are cached under a content hash (generated
source + compiler + flags), so the compiler runs once per distinct function.

When no C compiler is found, or compilation fails, the result wraps the
original (interpreted) Function instead; ``compiled`` is then ``False`` and
``reason`` says why.  Callers never need two code paths.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import casadi
import numpy as np

Parallelization = Literal["serial", "thread"]

DEFAULT_FLAGS: tuple[str, ...] = ("-O3", "-march=native", "-fPIC", "-shared")
"""Compiler flags; ``-march=native`` is safe because the cache is per machine."""

EXACT_FLAGS: tuple[str, ...] = ("-O1", "-ffp-contract=off", "-fPIC", "-shared")
"""Flags under which the compiled code computes what CasADi's interpreter computes, operation for operation:
no reassociation and no fused multiply-add (``-ffp-contract=off``), so results are bit-identical to the
interpreted Function (checked in ``tests/models/test_codegen.py``).  Used by :mod:`designkit.models.batch`."""

COMPILER_CANDIDATES: tuple[str, ...] = ("cc", "gcc", "clang")

MAX_CACHED_LIBRARIES = 256
"""The cache keeps at most this many shared libraries (the least recently built are removed): libraries are
keyed by content, and a simulation's content includes its gains, so the cache would otherwise grow without
bound."""


def default_cache_dir() -> Path:
    """Directory of cached shared libraries: :func:`designkit.cache.cache_dir` ``("codegen")``
    (``$DESIGNKIT_CACHE_DIR/codegen``, else ``$XDG_CACHE_HOME/designkit/codegen``, else
    ``~/.cache/designkit/codegen``)."""
    from designkit.cache import cache_dir

    return cache_dir("codegen")


def find_compiler() -> str | None:
    """Path of the first C compiler found on ``PATH`` (``cc``, ``gcc``, ``clang``), or None."""
    for name in COMPILER_CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    return None


@dataclass(frozen=True)
class CompiledFunction:
    """A CasADi Function, compiled to C when possible.

    Parameters
    ----------
    function : casadi.Function
        The Function to evaluate: the loaded shared library when ``compiled``,
        else the original Function.
    source : casadi.Function
        The original (interpreted) Function.
    compiled : bool
        True when ``function`` runs generated, compiled C code.
    reason : str
        Why compilation was skipped or failed; empty when ``compiled``.
    library : pathlib.Path or None
        The shared library, when ``compiled``.
    c_source : pathlib.Path or None
        The generated C file kept next to the library, when ``compiled``.

    Examples
    --------
    >>> import casadi
    >>> x = casadi.SX.sym("x", 2)
    >>> f = casadi.Function("sq", [x], [x * x], ["x"], ["y"])
    >>> cf = compile_function(f)
    >>> cf(np.array([1.0, 2.0]))["y"].ravel().tolist()
    [1.0, 4.0]
    """

    function: casadi.Function
    source: casadi.Function
    compiled: bool
    reason: str = ""
    library: Path | None = None
    c_source: Path | None = None
    _maps: dict = field(default_factory=dict, repr=False, compare=False, hash=False)

    @property
    def name(self) -> str:
        """Name of the Function."""
        return self.source.name()

    def __call__(self, *args: object) -> dict[str, np.ndarray]:
        """Evaluate once, positional inputs in the Function's order.

        Returns
        -------
        dict of str to numpy.ndarray
            Outputs by name, as dense 2-D arrays.
        """
        out = self.function.call(list(args))
        return {nm: np.asarray(casadi.DM(v)) for nm, v in zip(self.function.name_out(), out, strict=True)}

    def map(self, n: int, parallelization: Parallelization = "serial", *, threads: int = 1) -> casadi.Function:
        """The Function mapped over ``n`` column-stacked evaluations.

        Parameters
        ----------
        n : int
            Number of evaluations per call.
        parallelization : {"serial", "thread"}
            CasADi map strategy.
        threads : int
            Number of threads for ``"thread"``.

        Returns
        -------
        casadi.Function
            Inputs and outputs are horizontally concatenated along columns.
        """
        key = (n, parallelization, threads)
        if key not in self._maps:
            if parallelization == "thread":
                self._maps[key] = self.function.map(n, "thread", threads)
            else:
                self._maps[key] = self.function.map(n, parallelization)
        return self._maps[key]

    def evaluate_batch(
        self, *args: np.ndarray, parallelization: Parallelization = "serial", threads: int = 1
    ) -> dict[str, np.ndarray]:
        """Evaluate over N states in one call.

        Parameters
        ----------
        *args : numpy.ndarray
            One array per (column-vector) input, shaped ``(N, k)``: one row per
            state, ``k`` the input's number of elements.
        parallelization : {"serial", "thread"}
            CasADi map strategy.
        threads : int
            Number of threads for ``"thread"``.

        Returns
        -------
        dict of str to numpy.ndarray
            Each output of shape ``(N, rows, cols)``.
        """
        arrays = [np.atleast_2d(np.asarray(a, dtype=float)) for a in args]
        n = arrays[0].shape[0]
        mapped = self.map(n, parallelization, threads=threads)
        out = mapped.call([casadi.DM(a.T) for a in arrays])
        result = {}
        for k, name in enumerate(self.function.name_out()):
            rows, cols = self.function.size_out(k)
            flat = np.asarray(casadi.DM(out[k]))  # rows x (n * cols): [out_1 | out_2 | ...]
            result[name] = flat.reshape(rows, n, cols).transpose(1, 0, 2)
        return result


def _generate_source(f: casadi.Function) -> str:
    gen = casadi.CodeGenerator(f"{f.name()}.c", {"with_header": False, "verbose": False})
    gen.add(f)
    return gen.dump()


def _prune(cache: Path) -> None:
    """Remove the oldest libraries (and their sources) beyond :data:`MAX_CACHED_LIBRARIES`."""
    libraries = sorted(cache.glob("*.so"), key=lambda p: p.stat().st_mtime)
    for old in libraries[: max(0, len(libraries) - MAX_CACHED_LIBRARIES)]:
        for path in (old, old.with_suffix(".c")):
            with contextlib.suppress(OSError):
                path.unlink()


def _library_path(f: casadi.Function, cc: str, flags: tuple[str, ...], directory: Any) -> tuple[str, Path, Path]:
    source = _generate_source(f)
    digest = hashlib.sha256("\0".join([source, cc, *flags, casadi.__version__]).encode()).hexdigest()[:16]
    cache = Path(directory) if directory is not None else default_cache_dir()
    stem = f"{f.name()}_{digest}"
    return source, cache / f"{stem}.so", cache / f"{stem}.c"


def cached_library(f: casadi.Function, *, directory: str | os.PathLike[str] | None = None,
                   flags: tuple[str, ...] = DEFAULT_FLAGS, compiler: str | None = None) -> Path | None:
    """The shared library :func:`compile_function` would load for ``f`` if it is already built, else None."""
    cc = shutil.which(compiler) if compiler else find_compiler()
    if cc is None:
        return None
    _, library, _ = _library_path(f, cc, flags, directory)
    return library if library.exists() else None


def compile_function(
    f: casadi.Function,
    *,
    directory: str | os.PathLike[str] | None = None,
    flags: tuple[str, ...] = DEFAULT_FLAGS,
    compiler: str | None = None,
) -> CompiledFunction:
    """Generate C for ``f``, compile it (cached), and load it.

    Parameters
    ----------
    f : casadi.Function
        Function to compile (SX or MX based).
    directory : path-like, optional
        Cache directory; default :func:`default_cache_dir`.
    flags : tuple of str
        Compiler flags, default ``-O3 -march=native -fPIC -shared``.
    compiler : str, optional
        Compiler executable; default the first of ``cc``, ``gcc``, ``clang`` on ``PATH``.

    Returns
    -------
    CompiledFunction
        ``compiled=True`` with the loaded library, or the interpreted ``f``
        with ``compiled=False`` and the ``reason`` (no compiler, compiler
        error, unwritable cache directory).
    """
    cc = shutil.which(compiler) if compiler else find_compiler()
    if cc is None:
        wanted = compiler or " / ".join(COMPILER_CANDIDATES)
        return CompiledFunction(f, f, False, f"no C compiler found on PATH ({wanted}); using interpreted")
    source, library, c_file = _library_path(f, cc, flags, directory)
    cache = library.parent
    if not library.exists():
        try:
            cache.mkdir(parents=True, exist_ok=True)
            c_file.write_text(source)
            # Build to a private name, then rename atomically: safe with concurrent builders.
            fd, tmp = tempfile.mkstemp(suffix=".so", dir=cache)
            os.close(fd)
            proc = subprocess.run([cc, *flags, str(c_file), "-o", tmp, "-lm"], capture_output=True, text=True)
            if proc.returncode != 0:
                os.unlink(tmp)
                first = (proc.stderr.strip().splitlines() or ["unknown error"])[0]
                return CompiledFunction(f, f, False, f"compilation failed ({cc}): {first}")
            os.replace(tmp, library)
            _prune(cache)
        except OSError as exc:
            return CompiledFunction(f, f, False, f"cannot write to cache directory {cache}: {exc}")
    loaded = casadi.external(f.name(), str(library))
    return CompiledFunction(loaded, f, True, "", library, c_file)


def load_cached(f: casadi.Function, *, directory: str | os.PathLike[str] | None = None,
                flags: tuple[str, ...] = DEFAULT_FLAGS, compiler: str | None = None) -> CompiledFunction | None:
    """The :class:`CompiledFunction` :func:`compile_function` would return for ``f``, if its library is already
    built; else None.  Never runs the compiler (it generates the C source once, to hash it)."""
    cc = shutil.which(compiler) if compiler else find_compiler()
    if cc is None:
        return None
    _, library, c_file = _library_path(f, cc, flags, directory)
    if not library.exists():
        return None
    try:
        loaded = casadi.external(f.name(), str(library))
    except RuntimeError:  # an unloadable file under the expected name: not usable
        return None
    return CompiledFunction(loaded, f, True, "", library, c_file)
