"""Blocked, multi-threaded accumulation of Gram statistics (the hot loop of every fit).

Rows are cut into blocks of :data:`BLOCK_ROWS` counted from the start of a
trajectory. For each block Θ is formed (small enough to stay in the L2 cache)
and ``ΘᵀΘ``, ``Θᵀy``, ``Σ y²`` are added to one of :data:`LANES` running sums,
block ``i`` to lane ``i % LANES``; the lanes are summed in order at the end.
The result depends only on the rows and the block grid, never on how the rows
arrived (one array, chunks of any size, any number of threads), so a chunked
fit gives the bits of the in-memory fit.

Measured (m = 1e6, degree-5 polynomial of 3 variables, p = 56, this project's
2-core test machine, OpenBLAS): with numpy's default threaded BLAS on a loaded
machine a 4096-row ``ΘᵀΘ`` took 0.4 to 130 ms (threads spinning against other
processes); pinned to one BLAS thread it takes 0.45 ms (about 55 GFlop/s), and
blocks of 2048 to 4096 rows beat 32768 rows (which spill the cache) by 1.5-2x.
So BLAS runs single-threaded here and parallelism comes from our threads,
one per lane group, from one process-wide pool. Θ is written into one reused
buffer per thread: allocating a fresh 1.8 MB block each time cost ~450 page
faults per block, 0.23 s of page faults per 1e6 rows against 0.025 s of arithmetic.
"""
from __future__ import annotations

import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..errors import FeatureError
from ..optimizers.gram import GramStatistics

#: rows of Θ formed at a time (counted from the start of a trajectory)
BLOCK_ROWS = 4096
#: running sums the blocks are dealt to, in turn (summed in this order at the end)
LANES = 4
#: threads only pay off for calls with several blocks each (measured on 3-block trajectories)
MIN_BLOCKS_PER_THREAD = 8

_controller = None
_pool: ThreadPoolExecutor | None = None
_local = threading.local()


def _executor(threads: int) -> ThreadPoolExecutor:
    """One process-wide pool, created on first use (thread start-up measured ~1 ms each,
    which dominated fits of many short trajectories when pools were made per call)."""
    global _pool
    if _pool is None or _pool._max_workers < threads:
        _pool = ThreadPoolExecutor(threads, thread_name_prefix="discrepancy-gram")
    return _pool


def _buffer(p: int) -> np.ndarray:
    """This thread's reusable ``(p, BLOCK_ROWS)`` block of Θ (fresh 1.8 MB arrays cost
    ~450 page faults each: 0.23 s per 1e6 rows against 0.025 s of arithmetic)."""
    buffers = getattr(_local, "buffers", None)
    if buffers is None:
        buffers = _local.buffers = {}
    if p not in buffers:
        buffers[p] = np.empty((p, BLOCK_ROWS))
    return buffers[p]


def single_threaded_blas():
    """Context manager limiting BLAS to one thread (threadpoolctl), created once: on tall,
    thin matrices its threads cost far more than they save (an SVD of 25,000 x 12 takes
    0.14 s CPU on two threads against 0.008 s on one)."""
    global _controller
    if _controller is None:
        from threadpoolctl import ThreadpoolController
        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")


def default_threads() -> int:
    """Worker threads: the CPUs this process may use, at most :data:`LANES`."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cpus = os.cpu_count() or 1
    return max(1, min(LANES, cpus))


def statistics_bytes(p: int, n: int, n_folds: int = 5) -> int:
    """Bytes a fit's statistics of ``p`` columns and ``n`` targets take at their peak: the
    total and :data:`LANES` running lanes, each with its folds, a few solver copies, and one
    Θ block per thread."""
    copies = (LANES + 1) * (n_folds + 1) + 4
    return 8 * (copies * p * (p + n) + LANES * BLOCK_ROWS * (p + n))


class BlockAccumulator:
    """Running Gram statistics of ``Θ = transform(z)`` against targets ``y``.

    Args:
        transform: a fitted library's ``transform(Z, out=...)``: ``Z (k, n_variables)`` to
            Θ ``(k, p)`` written into ``out``.
        total: the statistics to add to (its folds, if any, say how rows are dealt out);
            the next row added is data row ``total.count``.
        n_threads: threads to use (default :func:`default_threads`); does not change the result.
        names: the columns' and variables' names, for the message when a column is not
            finite (:class:`Names`).

    Feed rows of one trajectory with :meth:`add`; every call but the last of a
    trajectory must hold a whole number of blocks (:mod:`~discrepancy.fitting.streaming`
    carries the remainder over), then :meth:`finish_trajectory` before the next one.
    """

    def __init__(self, transform: Callable[[np.ndarray], np.ndarray], total: GramStatistics,
                 *, n_threads: int | None = None, names: Names | None = None):
        self.transform, self.names = transform, names
        self.total = total
        self.p, self.n = total.p, total.n
        self.n_threads = default_threads() if n_threads is None else max(1, int(n_threads))
        self._row = total.count
        self._new_lanes()

    def _new_lanes(self) -> None:
        self._lanes = [self.total.empty_like() for _ in range(LANES)]
        self._blocks = 0

    def add(self, z: np.ndarray, y: np.ndarray, signal: np.ndarray | None = None,
            weight: np.ndarray | None = None) -> None:
        """Add rows ``z`` ``(k, n_variables)`` with targets ``y`` ``(k, n)`` (and the
        derivatives ``signal`` ``(k, n)`` they came from, default ``y``; and the rows'
        weights ``(k,)``, default 1)."""
        k = z.shape[0]
        if k == 0:
            return
        signal = y if signal is None else signal
        starts = list(range(0, k, BLOCK_ROWS))
        work = [[] for _ in range(LANES)]
        for b, s in enumerate(starts):
            work[(self._blocks + b) % LANES].append(s)
        self._blocks += len(starts)
        first, self._row = self._row, self._row + k
        threads = max(1, min(self.n_threads, len(starts) // MIN_BLOCKS_PER_THREAD))
        with single_threaded_blas():
            if threads == 1:
                for i in range(LANES):
                    self._run(i, work[i], z, y, signal, weight, first)
            else:
                groups = [list(range(i, LANES, threads)) for i in range(threads)]
                list(_executor(threads).map(
                    lambda g: [self._run(i, work[i], z, y, signal, weight, first) for i in g],
                    groups))

    def _run(self, i, starts, z, y, signal, weight, first) -> None:
        """Add the blocks starting at rows ``starts`` (data row ``first + s``) to lane ``i``.

        Each block fills rows of ``A = [Θ | y]ᵀ`` ``(p + n, k)`` and adds ``A Aᵀ``: one
        product gives ``ΘᵀΘ``, ``Θᵀy`` and ``yᵀy`` (a separate ``Θᵀy`` with n = 3 columns
        measured a third of the ``ΘᵀΘ`` time; the extra rows cost ~10 %). With folds, the
        product is taken per piece of the block that lies in one fold's segment.
        """
        p, lane = self.p, self._lanes[i]
        buffer = _buffer(p + self.n)
        for s in starts:
            zb = z[s:s + BLOCK_ROWS]
            k = zb.shape[0]
            self.transform(zb, out=buffer[:p, :k].T)
            buffer[p:, :k] = y[s:s + BLOCK_ROWS].T
            sb = signal[s:s + BLOCK_ROWS]
            if weight is not None:  # rows times sqrt(w): the sums become weighted sums
                root = np.sqrt(weight[s:s + BLOCK_ROWS])
                buffer[:, :k] *= root
                sb = sb * root[:, None]
            if lane.folds is None:
                finite = _add_product(lane, buffer[:, :k], sb, p)
            else:
                finite = all([_add_product(lane.folds[fold], buffer[:, lo:hi], sb[lo:hi], p)
                              for lo, hi, fold in lane.pieces(first + s, k)])
            if not finite:
                raise not_finite(buffer[:, :k], zb, first + s, p, self.names)

    def finish_trajectory(self) -> None:
        """Add the lanes of the current trajectory to ``total``, in lane order."""
        for lane in self._lanes:
            if lane.folds is not None:
                lane._sum_folds()
            self.total += lane
        self._new_lanes()


def _add_product(stats: GramStatistics, a: np.ndarray, signal: np.ndarray, p: int) -> bool:
    """Add the sums of ``a = [Θ | y]ᵀ``; returns whether they are finite (every column of
    ``a`` is finite and its squares do not overflow exactly when ``a aᵀ``'s diagonal is)."""
    g = a @ a.T
    stats.gram += g[:p, :p]
    stats.rhs += g[:p, p:]
    stats.yy += np.diagonal(g[p:, p:])
    stats.signal += np.einsum("ij,ij->j", signal, signal)
    stats.count += a.shape[1]
    return bool(np.all(np.isfinite(np.diagonal(g))))


def not_finite(block: np.ndarray, z: np.ndarray, row: int, p: int,
               names: Names | None) -> FeatureError:
    """The error naming the first column of ``block`` (``[Θ | y]ᵀ`` ``(p + n, k)`` of data
    rows ``row...`` with variables ``z``) that is not finite, or whose squares overflow."""
    names = names or Names([f"column {j}" for j in range(p)], [])
    bad = ~np.isfinite(block)
    if bad.any():
        i, j = (int(v) for v in np.argwhere(bad.T)[0])
        what = f"library column {names.columns[j]!r}" if j < p else \
            f"the target of equation {j - p} (x_dot - prior)"
        at = names.values(z[i]) if j < p else ""
        return FeatureError(f"{what} is {block[j, i]} at row {row + i}{at}: the term is "
                            "undefined or overflows there (remove the term, or those rows)")
    with np.errstate(over="ignore"):
        j = int(np.argmax(~np.isfinite(np.einsum("ij,ij->i", block, block))))
    what = f"library column {names.columns[j]!r}" if j < p else f"the target of equation {j - p}"
    return FeatureError(f"{what} overflows: the sum of its squares over rows {row}.."
                        f"{row + block.shape[1] - 1} exceeds 1.8e308 (largest magnitude "
                        f"{np.max(np.abs(block[j])):.3g}). Scale the data or use a smaller "
                        "library")


@dataclass(frozen=True)
class Names:
    """Names of Θ's columns and of the variables ``z`` (empty when ``z`` is not variables,
    as in the weak form), for messages."""

    columns: list[str]
    variables: list[str]

    def values(self, z_row: np.ndarray) -> str:
        """`` (x1 = -0.5, x2 = 1)`` for one row of ``z``."""
        if len(self.variables) != len(z_row):
            return ""
        return " (" + ", ".join(f"{n} = {v:.6g}" for n, v in zip(self.variables, z_row,
                                                                 strict=True)) + ")"


def accumulate(stats: GramStatistics, transform, z: np.ndarray, y: np.ndarray,
               signal: np.ndarray | None = None, weight: np.ndarray | None = None, *,
               n_threads: int | None = None, names: Names | None = None) -> GramStatistics:
    """Add the statistics of one whole trajectory's rows ``z``, ``y`` (derivatives
    ``signal``, row weights ``weight``) to ``stats`` in place; its rows follow the
    ``stats.count`` rows before."""
    acc = BlockAccumulator(transform, stats, n_threads=n_threads, names=names)
    acc.add(z, y, signal, weight)
    acc.finish_trajectory()
    return stats
