"""CasADi functions compiled to C once, cached on disk, where it pays.

CasADi evaluates a Function in its virtual machine, a few nanoseconds per instruction. The
same function generated as C (CasADi's code generator) and compiled with ``-O1`` runs
about ten times faster: the sensitivity block of a 2-state model with 10 free
coefficients over 25,000 samples took 0.07 s of CPU compiled against 0.67 s in the
virtual machine (``-O2`` was no faster and took twice as long to compile). Compiling
takes 0.5-2 s, so it is done only when the work it would save is larger
(:func:`worth_compiling`), and the shared library is kept in a cache folder keyed by a
hash of the generated source, so the next fit of the same model structure loads it in
milliseconds. CasADi does the code generation; written here is only the cache and the
decision, which no library we use provides. Without a C compiler (``$CC`` or ``cc``) or
when compiling fails, the caller keeps the virtual machine: same numbers, slower.

The cache folder is ``$DISCREPANCY_CACHE_DIR``, else ``$XDG_CACHE_HOME/discrepancy``
(``~/.cache/discrepancy``), else a folder in the system's temporary directory.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from .casadi_form import _casadi

#: compiler flags (``-O1``: as fast as ``-O2`` here at half the compile time)
FLAGS = ("-O1", "-shared", "-fPIC")
#: seconds per instruction in CasADi's virtual machine, and the compiled code's speed-up
#: (both measured on the output-error sensitivity blocks; used only to decide)
VM_SECONDS_PER_INSTRUCTION = 6e-9
COMPILED_SPEEDUP = 8.0
#: compile time model: seconds = COMPILE_BASE + COMPILE_PER_CHARACTER * len(source)
COMPILE_BASE, COMPILE_PER_CHARACTER = 0.3, 2e-5
#: a compilation that takes longer than this is abandoned (the virtual machine is used)
COMPILE_TIMEOUT = 300


def compiler() -> str | None:
    """The C compiler command (``$CC`` or ``cc``) if it is on the path, else ``None``."""
    return shutil.which(os.environ.get("CC", "cc"))


def cache_dir() -> Path:
    """The folder compiled functions are kept in (created when missing)."""
    given = os.environ.get("DISCREPANCY_CACHE_DIR")
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    user = getattr(os, "getuid", lambda: 0)()
    for folder in (given, os.path.join(base, "discrepancy") if not given else None,
                   os.path.join(tempfile.gettempdir(), f"discrepancy-{user}")):
        if folder is None:
            continue
        try:
            os.makedirs(folder, exist_ok=True)
        except OSError:
            continue
        if os.access(folder, os.W_OK):
            return Path(folder)
    return Path(tempfile.mkdtemp(prefix="discrepancy-"))


def source_of(function) -> str:
    """C source of a CasADi Function (its name is the C symbol)."""
    ca = _casadi()
    generator = ca.CodeGenerator(f"{function.name()}.c", {"with_header": False})
    generator.add(function)
    return generator.dump()


def _library_path(function, source: str) -> Path:
    ca = _casadi()
    key = hashlib.sha256("\n".join([source, " ".join(FLAGS), compiler() or "",
                                    ca.__version__]).encode()).hexdigest()[:20]
    return cache_dir() / f"{function.name()}_{key}.so"


def worth_compiling(function, instructions: float, source: str | None = None) -> bool:
    """Whether compiling ``function`` pays for evaluating ``instructions`` virtual-machine
    instructions with it: true when it is cached, else when the time it saves exceeds the
    estimated compile time (and a compiler exists)."""
    if compiler() is None:
        return False
    source = source_of(function) if source is None else source
    if _library_path(function, source).exists():
        return True
    saved = instructions * VM_SECONDS_PER_INSTRUCTION * (1 - 1 / COMPILED_SPEEDUP)
    return saved > COMPILE_BASE + COMPILE_PER_CHARACTER * len(source)


def compile_function(function, source: str | None = None):
    """``function`` compiled to C and loaded (``casadi.external``), or ``None`` when there
    is no compiler or compiling fails."""
    ca = _casadi()
    cc = compiler()
    if cc is None:
        return None
    source = source_of(function) if source is None else source
    library = _library_path(function, source)
    if not library.exists():
        with tempfile.TemporaryDirectory(dir=library.parent) as work:
            c_file, built = Path(work) / "f.c", Path(work) / "f.so"
            c_file.write_text(source)
            try:
                subprocess.run([cc, *FLAGS, str(c_file), "-o", str(built), "-lm"], check=True,
                               capture_output=True, timeout=COMPILE_TIMEOUT)
            except (OSError, subprocess.SubprocessError):
                return None
            os.replace(built, library)          # atomic: other processes see all or nothing
    try:
        return ca.external(function.name(), str(library))
    except RuntimeError:
        return None
