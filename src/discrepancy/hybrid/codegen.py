"""CasADi functions as compiled C: generated once, compiled with the machine's C compiler,
cached on disk by the hash of their source, and loaded back as ``casadi.external``.

CasADi's own ``jit`` option compiles at every construction; here the shared library is kept
under the cache directory (``$DISCREPANCY_CACHE``, else ``$XDG_CACHE_HOME/discrepancy``,
else ``~/.cache/discrepancy``) named by the SHA-256 of the generated C, so a second process,
a second controller with the same settings, or tomorrow's run loads it in milliseconds. A
library is written to a temporary name and renamed into place, so processes compiling the
same source at once do not read half a file. Without a C compiler (``$CC``, ``cc``,
``gcc``, ``clang``), or when compiling fails, the function is returned as it was (CasADi's
virtual machine evaluates it, slower, same numbers) with a :class:`CompilationWarning`.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ..constraints import check_argument
from ..errors import CompilationWarning
from .casadi_form import casadi_module

#: optimisation flag. -O1 gave most of -O2's speed on CasADi's straight-line code at a
#: fraction of its compile time (the cart MPC's condensing: 21 s against 160 s); -Og runs
#: as fast again and compiles in less than half of -O1's time (GCC 12, CPU of the compiler
#: and of one call, measured side by side: the cart MPC's condensing 12.9 s -> 5.2 s,
#: 58 -> 56 us a call, its linearisation 6.4 s -> 2.2 s, 30 -> 34 us; a prediction-error
#: filter block 0.83 s -> 0.57 s, 62 -> 44 us, its reverse derivative 124 -> 126 us).
#: Neither lets the compiler reorder floating-point arithmetic: the numbers are the same
OPTIMISATION = "-Og"


def cache_dir() -> Path:
    """Directory of the compiled libraries (created when first needed)."""
    root = os.environ.get("DISCREPANCY_CACHE")
    if root:
        return Path(root).expanduser() / "casadi"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base).expanduser() / "discrepancy" / "casadi"


def compiler() -> str | None:
    """The C compiler to use, or None: ``$CC``, else the first of cc, gcc, clang on PATH."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name.split()[0]):
            return name
    return None


def compiled(function, *, enabled=True, reverse=False):
    """``function`` as compiled C (a ``casadi.external`` of the same name and signature), or
    ``function`` itself when ``enabled`` is False or compiling is not possible (warned).

    Args:
        function: a ``casadi.Function`` that supports code generation (SX functions, MX
            graphs of them; not every plugin does).
        enabled: False to skip compiling (returns ``function``).
        reverse: also compile its reverse-mode derivative (CasADi finds it in the library
            by its name, ``adj1_<name>``), so that gradients of graphs calling the external
            stay compiled.
    """
    check_argument("compile", enabled, bool)
    check_argument("reverse", reverse, bool)
    if not enabled:
        return function
    ca = casadi_module()
    name = function.name()
    try:
        with tempfile.TemporaryDirectory() as tmp:
            generator = ca.CodeGenerator(f"{name}.c", {"with_header": False})
            generator.add(function)
            if reverse:
                generator.add(function.reverse(1))
            generator.generate(tmp + os.sep)
            source = Path(tmp, f"{name}.c").read_bytes()
            digest = hashlib.sha256(source + OPTIMISATION.encode()).hexdigest()[:20]
            library = cache_dir() / f"{name}_{digest}.so"
            if not library.exists():
                _compile(Path(tmp, f"{name}.c"), library)
        return ca.external(name, str(library))
    except (OSError, RuntimeError, subprocess.SubprocessError) as e:
        warnings.warn(f"could not compile {name!r} ({type(e).__name__}: {str(e)[:200]}); it "
                      "runs in CasADi's virtual machine instead (same results, slower). "
                      "Install a C compiler (cc, gcc or clang, or set CC) to compile it",
                      CompilationWarning, stacklevel=3)
        return function


def _compile(source: Path, library: Path) -> None:
    cc = compiler()
    if cc is None:
        raise OSError("no C compiler found ($CC, cc, gcc, clang)")
    library.parent.mkdir(parents=True, exist_ok=True)
    fd, partial = tempfile.mkstemp(suffix=".so", dir=library.parent)
    os.close(fd)
    try:
        # CasADi's code for empty copies passes an integer as a pointer, an error in GCC 14
        # and recent clang unless this warning is switched off
        subprocess.run([*cc.split(), OPTIMISATION, "-Wno-int-conversion", "-shared", "-fPIC",
                        "-o", partial, str(source), "-lm"], check=True, capture_output=True,
                       timeout=900)
        os.replace(partial, library)
    except subprocess.CalledProcessError as e:
        raise RuntimeError(f"{cc} failed: {e.stderr.decode(errors='replace')[:300]}") from None
    finally:
        if os.path.exists(partial):
            os.unlink(partial)


class BufferedFunction:
    """A CasADi Function called on numpy arrays through its buffer interface: its inputs and
    first output are bound once to preallocated arrays, so a call costs about a microsecond
    of overhead instead of the tens a ``Function.__call__`` spends converting its arguments
    (for the output-error blocks, converting each result cost as much as computing it).

    ``call(*args)`` copies each argument into its input (broadcast to the declared shape;
    a view of the previous result is fine, it is copied first) and returns the first output
    ``(size1, size2)`` as a view of a buffer the next call overwrites: copy what you keep.
    Not thread-safe: one object per thread. Dense inputs and outputs only."""

    def __init__(self, function):
        self.function = function
        self._buffer, self._evaluate = function.buffer()
        self._args = [np.zeros((function.size1_in(i), function.size2_in(i)), order="F")
                      for i in range(function.n_in())]
        for i, arg in enumerate(self._args):
            self._buffer.set_arg(i, memoryview(arg.ravel(order="K")))
        self._result = np.zeros(function.nnz_out(0))
        self._buffer.set_res(0, memoryview(self._result))
        self._shape = (function.size2_out(0), function.size1_out(0))

    def __call__(self, *args) -> np.ndarray:
        for arg, value in zip(self._args, args, strict=True):
            value = np.asarray(value, dtype=float)
            arg[...] = value.reshape(-1, 1) if value.ndim < 2 else value   # a column
        self._evaluate()
        return self._result.reshape(self._shape).T
