"""Chunked fitting: data that arrive in pieces, or do not fit in memory.

What a chunk is
    A :class:`Chunk` holds consecutive rows of ONE trajectory in time order:
    ``x`` ``(k, n)`` and optionally ``t`` ``(k,)`` (the times of these rows),
    ``u`` ``(k, r)`` and ``x_dot`` ``(k, n)``. A plain array is a chunk of ``x``;
    a mapping with keys among ``x, t, u, x_dot`` is converted. Chunks without
    ``t`` are placed on the grid ``t = row * step`` with ``step`` the ``t`` given to
    ``fit`` (default 1), counted from the trajectory's first row, exactly as the
    in-memory fit does.

What a trajectory is
    ``model.fit(iterator_of_chunks)`` is one trajectory; a list of such
    iterators, or a :class:`ChunkSource` (files, see :mod:`discrepancy.data.sources`),
    gives several. Derivatives never straddle the join of two trajectories.

Exactness
    A local differentiation method (``halo`` rows each side, e.g. finite
    differences or Savitzky–Golay) is applied on windows of ``2 halo`` carried
    rows plus the next chunk, keeping only rows whose stencil lies inside the
    window (and the true ends of the trajectory), so every derivative is the one
    the whole trajectory gives. Rows then go through the same fixed block grid
    as the in-memory fit (:mod:`discrepancy.accumulate`), so the Gram statistics,
    and the model, equal the in-memory ones (to rounding in the derivative's
    time step). Global methods (``halo`` None: splines, trend filtering, Kalman)
    are refused: their derivative at one row depends on the whole trajectory;
    differentiate first and stream ``x_dot``.

Memory is bounded by about two chunks plus a 4096-row block of Θ.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import replace

import numpy as np

from .accumulate import BLOCK_ROWS, BlockAccumulator
from .data.chunks import (  # noqa: F401  (Chunk, ChunkSource, peek_layout: public here too)
    FIELDS,
    Chunk,
    ChunkSource,
    IterableSource,
    _Layout,
    _validated,
    as_source,
    peek_layout,
    step_of,
)
from .data.trajectory import Trajectory
from .errors import ParameterError, ShapeError

__all__ = ["Chunk", "ChunkSource", "IterableSource", "chunk_statistics", "stream_statistics"]


# ------------------------------------------------------------------ stitching
def _concat(a: Chunk, b: Chunk) -> Chunk:
    return Chunk(**{f: None if getattr(a, f) is None else
                    np.concatenate([getattr(a, f), getattr(b, f)]) for f in FIELDS},
                 where=b.where)


def residual_rows(setup, chunks: Iterable[Chunk]) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield ``(z, y)`` for consecutive rows of one trajectory, equal to ``setup.residual``
    of the whole trajectory (chunks validated)."""
    for xs, xd, lo, hi in _stitched(chunks, setup.differentiation):
        if hi > lo:
            yield setup.residual(Trajectory(xs.t[lo:hi], xs.x[lo:hi], None if xs.u is None
                                            else xs.u[lo:hi], xd[lo:hi]))


def _stitched(chunks, method):
    """Yield ``(window, x_dot_or_smoothed, lo, hi)``; rows ``lo:hi`` of the window are exact.

    A window (carried rows plus one chunk) is differentiated once the next chunk shows it
    is not the trajectory's last; chunks with ``x_dot`` pass straight through.
    """
    window, first = None, True
    for chunk in chunks:
        if chunk.x_dot is not None:
            yield chunk, chunk.x_dot, 0, chunk.n_rows
            continue
        h = method.halo
        if h is None:
            raise ParameterError(
                f"{method!r} is a global differentiation method (the derivative at one row "
                "depends on the whole trajectory), so it cannot be applied chunk by chunk; "
                "use FiniteDifference() or SavitzkyGolay(), or compute x_dot first and stream "
                "it with the chunks")
        if window is not None and window.n_rows >= max(method.min_samples, 2 * h + 1):
            xs, xd = method(window.x, window.t)  # not the last window: a chunk follows
            yield replace(window, x=xs), xd, (0 if first else h), window.n_rows - h
            window, first = window.rows(window.n_rows - 2 * h), False
        window = chunk if window is None else _concat(window, chunk)
    if window is not None:
        xs, xd = method(window.x, window.t)
        yield replace(window, x=xs), xd, (0 if first else method.halo), window.n_rows


# ------------------------------------------------------------------ fitting
class _RowFeeder:
    """Passes rows to a BlockAccumulator on the trajectory's block grid: whole blocks go
    through as views, a partial block is kept (copied) until the next rows complete it."""

    def __init__(self, acc: BlockAccumulator):
        self.acc = acc
        self.z, self.y, self.rows = [], [], 0

    def add(self, z, y):
        if self.rows:
            if self.rows + z.shape[0] < BLOCK_ROWS:
                self._keep(z, y)
                return
            need = BLOCK_ROWS - self.rows
            self.acc.add(np.concatenate([*self.z, z[:need]]), np.concatenate([*self.y, y[:need]]))
            self.z, self.y, self.rows = [], [], 0
            z, y = z[need:], y[need:]
        cut = (z.shape[0] // BLOCK_ROWS) * BLOCK_ROWS
        if cut:
            self.acc.add(z[:cut], y[:cut])
        if cut < z.shape[0]:
            self._keep(z[cut:], y[cut:])

    def _keep(self, z, y):
        self.z.append(z.copy())
        self.y.append(y.copy())
        self.rows += z.shape[0]

    def end_trajectory(self):
        if self.rows:
            self.acc.add(np.concatenate(self.z), np.concatenate(self.y))
        self.z, self.y, self.rows = [], [], 0
        self.acc.finish_trajectory()


def stream_statistics(source: ChunkSource, step: float, setup_for: Callable, *,
                      progress: bool | None = None, n_threads: int | None = None):
    """``(setup, stats)``: the Gram statistics of all rows of ``source``.

    ``setup_for(n_states, n_inputs)`` gives the :class:`~discrepancy.models.setup.FitSetup`
    once the first chunk shows the layout (e.g. ``model.make_setup``); every later
    trajectory must have the same layout.
    """
    from tqdm.auto import tqdm

    setup = acc = feeder = layout = None
    with tqdm(total=source.n_samples, unit=" samples", unit_scale=True, desc="fit",
              disable=None if progress is None else not progress) as bar:
        for k, items in enumerate(source.trajectories()):
            stream = _validated(items, k, step, layout)
            first = next(stream, None)
            if first is None:
                raise ShapeError(f"trajectory {k} of x has no rows")
            if setup is None:
                layout = first[0]
                setup = setup_for(layout.n, layout.r)
                acc = BlockAccumulator(setup.library.transform, setup.n_features, layout.n,
                                       n_threads=n_threads)
                feeder = _RowFeeder(acc)

            def counted(first=first, stream=stream):
                for _, chunk in _chain(first, stream):
                    yield chunk
                    bar.update(chunk.n_rows)

            for z, y in residual_rows(setup, counted()):
                feeder.add(z, y)
            feeder.end_trajectory()
    if setup is None:
        raise ShapeError("x holds no trajectories")
    return setup, acc.total


def _chain(first, rest):
    yield first
    yield from rest


def chunk_statistics(model, x, *, t=None, u=None, x_dot=None):
    """``(setup, stats)`` of chunked input for ``model.fit`` (see the module docstring)."""
    if u is not None or x_dot is not None:
        raise ParameterError("with chunked x, give u and x_dot inside the chunks "
                             "(Chunk(x, u=..., x_dot=...)), not as separate arguments")
    return stream_statistics(as_source(x), step_of(t), model.make_setup)
