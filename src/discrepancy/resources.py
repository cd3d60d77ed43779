"""Refusing work that cannot fit in memory, before anything large is allocated.

Sizes grow from small arguments: a degree-10 polynomial library of 50 states has 7.5e10
columns, ``simulate(x0, 10**12)`` on a map asks for 1e12 rows, a 4 kB NPZ file can declare
a 32 GB array. Every place that would allocate something whose size the user's arguments
decide first estimates it here, with exact integer arithmetic, and raises
:class:`~discrepancy.errors.ResourceError` (a ``MemoryError``) saying how big, against
what limit, and what to do instead:

* :func:`check_features`: the number of library columns, counted combinatorially before
  any expression is built, at most :data:`MAX_FEATURES`;
* :func:`check_memory`: bytes of one allocation (the Gram statistics of a library, a
  simulation's output, an array read from a file) against :func:`memory_budget`.
"""
from __future__ import annotations

import math
import os

from .errors import ResourceError

__all__ = ["MAX_FEATURES", "MEMORY_FRACTION", "MEMORY_LIMIT", "check_features", "check_memory",
           "memory_budget", "n_bytes"]

#: most columns a library may have (Θᵀ Θ of 50,000 columns alone is 20 GB)
MAX_FEATURES = 50_000
#: bytes one allocation may take; ``None``: :data:`MEMORY_FRACTION` of the memory this
#: process may use (the machine's, or less under ``ulimit -v``). Set it to change the limit.
MEMORY_LIMIT: int | None = None
#: share of the memory this process may use that one allocation may take by default
MEMORY_FRACTION = 0.8
#: allocations this small are never refused (and cost no look-up of the budget)
ALWAYS_ALLOWED = 2**26

#: what to do instead, for the advice in messages
CHUNKED = ("fit the data in chunks (an iterator of Chunk, HDF5Source, or a dask array): "
           "memory then grows with the library, not with the data")
SMALLER_LIBRARY = ("Use a smaller library (a lower degree, fewer frequencies, or variables= to "
                   "restrict it to some states)")


def n_bytes(shape, itemsize: int = 8) -> int:
    """Bytes of an array of ``shape`` (Python integers: no overflow)."""
    return math.prod(int(s) for s in shape) * itemsize


def memory_budget() -> int:
    """Bytes one allocation may take: :data:`MEMORY_LIMIT`, or :data:`MEMORY_FRACTION` of
    the smaller of physical memory and what ``ulimit -v`` leaves this process."""
    if MEMORY_LIMIT is not None:
        return int(MEMORY_LIMIT)
    try:
        import resource
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, ValueError, OSError):  # not a POSIX system: no limit known
        return 2**63
    if soft != resource.RLIM_INFINITY:
        total = min(total, max(0, soft - _address_space()))
    return int(MEMORY_FRACTION * total)


def _address_space() -> int:
    """Virtual memory this process already uses (what ``ulimit -v`` counts), 0 if unknown."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _size(nbytes: int) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{nbytes} bytes"


def check_memory(what: str, nbytes: int, advice: str) -> None:
    """Raise ResourceError when ``nbytes`` (for ``what``, e.g. ``"the simulation's output
    (1e12 steps x 2 states)"``) exceed :func:`memory_budget`; ``advice`` says what to do."""
    if nbytes <= ALWAYS_ALLOWED:
        return
    budget = memory_budget()
    if nbytes > budget:
        raise ResourceError(f"{what} would need {_size(nbytes)}; at most {_size(budget)} may be "
                            f"allocated here (discrepancy.resources.MEMORY_LIMIT). {advice}")


def check_features(owner: str, count: int, advice: str = SMALLER_LIBRARY) -> None:
    """Raise ResourceError when a library ``owner`` would have more than
    :data:`MAX_FEATURES` columns (``count``, computed before building them)."""
    if count > MAX_FEATURES:
        shown = f"{count:,}" if count < 10**15 else f"about 10^{len(str(count)) - 1}"
        raise ResourceError(f"{owner} would have {shown} columns; at most {MAX_FEATURES:,} "
                            f"are allowed (a fit needs memory for their square). {advice}")
