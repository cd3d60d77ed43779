"""Chunked fitting: data that arrive in pieces, or do not fit in memory.

What a chunk is
    A :class:`~discrepancy.data.chunks.Chunk` holds consecutive rows of ONE trajectory in
    time order: ``x`` ``(k, n)`` and optionally ``t`` ``(k,)`` (the times of these rows),
    ``u`` ``(k, r)`` and ``x_dot`` ``(k, n)``. A plain array is a chunk of ``x``;
    a mapping with keys among ``x, t, u, x_dot`` is converted. Chunks without
    ``t`` are placed on the grid ``t = row * step`` with ``step`` the ``t`` given to
    ``fit`` (default 1), counted from the trajectory's first row, exactly as the
    in-memory fit does.

What a trajectory is
    ``model.fit(iterator_of_chunks)`` is one trajectory; a list of such
    iterators, or a :class:`~discrepancy.data.chunks.ChunkSource` (files, see
    :mod:`discrepancy.data.sources`), gives several. Derivatives never straddle the join
    of two trajectories.

Exactness
    A local differentiation method (``halo`` rows each side, e.g. finite
    differences or Savitzky–Golay) is applied on windows of ``2 halo`` carried
    rows plus the next chunk, keeping only rows whose stencil lies inside the
    window (and the true ends of the trajectory), so every derivative is the one
    the whole trajectory gives. Rows then go through the same fixed block grid
    as the in-memory fit (:mod:`discrepancy.fitting.accumulate`), so the Gram statistics,
    and the model, equal the in-memory ones (to rounding in the derivative's
    time step). Global methods (``halo`` None: splines, trend filtering, Kalman)
    are refused: their derivative at one row depends on the whole trajectory;
    differentiate first and stream ``x_dot``.

Memory is bounded by about two chunks plus a 4096-row block of Θ.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

import numpy as np
from tqdm.auto import tqdm

from ..data.chunks import FIELDS, Chunk, ChunkSource, as_source, step_of, validated_chunks
from ..data.trajectory import Trajectory
from ..errors import ParameterError, ShapeError
from .accumulate import BLOCK_ROWS, BlockAccumulator
from .setup import sample_rows

__all__ = ["chunk_statistics", "source_setup", "stream_statistics"]


# ------------------------------------------------------------------ stitching
def _concat(a: Chunk, b: Chunk) -> Chunk:
    return Chunk(**{f: None if getattr(a, f) is None else
                    np.concatenate([getattr(a, f), getattr(b, f)]) for f in FIELDS},
                 where=b.where)


def residual_rows(setup, chunks: Iterable[Chunk]) -> Iterator[tuple[np.ndarray, ...]]:
    """Yield ``(z, y, x_dot[, weight])`` for consecutive rows of one trajectory, equal to
    ``setup.rows`` of the whole trajectory (chunks validated)."""
    for window, lo, hi in _stitched(chunks, setup.differentiation):
        if hi > lo:
            rows = setup.rows(Trajectory(window.t, window.x, window.u, window.x_dot))
            weight = () if window.weight is None else (window.weight[:len(rows[0])],)
            yield tuple(a[lo:hi] for a in (*rows, *weight))


def _stitched(chunks, method):
    """Yield ``(window, lo, hi)``: rows ``lo:hi`` of ``setup.rows(window)`` are exactly
    those of the whole trajectory.

    A window (carried rows plus one chunk) is passed on once the next chunk shows it is not
    the trajectory's last; chunks with ``x_dot`` pass straight through.
    """
    window, first = None, True
    for chunk in chunks:
        if chunk.x_dot is not None:
            yield chunk, 0, chunk.n_rows
            continue
        h = method.halo
        if method.dropped_rows != (0, 0):
            raise ParameterError(f"{method!r} drops each trajectory's end rows, which a "
                                 "stream only knows at its end; stream with "
                                 "drop_endpoints=False (or fit in memory)")
        if h is None:
            raise ParameterError(
                f"{method!r} is a global differentiation method (the derivative at one row "
                "depends on the whole trajectory), so it cannot be applied chunk by chunk; "
                "use FiniteDifference() or SavitzkyGolay(), or compute x_dot first and stream "
                "it with the chunks")
        if window is not None and window.n_rows >= max(method.min_samples, 2 * h + 1):
            yield window, (0 if first else h), window.n_rows - h  # a chunk follows
            window, first = window.rows(window.n_rows - 2 * h), False
        window = chunk if window is None else _concat(window, chunk)
    if window is not None:
        yield window, (0 if first else method.halo), window.n_rows


# ------------------------------------------------------------------ fitting
class _RowFeeder:
    """Passes rows to a BlockAccumulator on the trajectory's block grid: whole blocks go
    through as views, a partial block is kept (copied) until the next rows complete it.
    Rows are tuples of arrays with the same number of rows (``z, y, x_dot``)."""

    def __init__(self, acc: BlockAccumulator):
        self.acc = acc
        self.kept, self.rows = [], 0

    def add(self, *arrays):
        if self.rows:
            if self.rows + arrays[0].shape[0] < BLOCK_ROWS:
                self._keep(arrays)
                return
            need = BLOCK_ROWS - self.rows
            self.acc.add(*[np.concatenate([*old, new[:need]])
                           for old, new in zip(zip(*self.kept, strict=True), arrays, strict=True)])
            self.kept, self.rows = [], 0
            arrays = [a[need:] for a in arrays]
        cut = (arrays[0].shape[0] // BLOCK_ROWS) * BLOCK_ROWS
        if cut:
            self.acc.add(*[a[:cut] for a in arrays])
        if cut < arrays[0].shape[0]:
            self._keep([a[cut:] for a in arrays])

    def _keep(self, arrays):
        self.kept.append([a.copy() for a in arrays])
        self.rows += arrays[0].shape[0]

    def end_trajectory(self):
        if self.rows:
            self.acc.add(*[np.concatenate(parts) for parts in zip(*self.kept, strict=True)])
        self.kept, self.rows = [], 0
        self.acc.finish_trajectory()


def stream_statistics(source: ChunkSource, step: float, make_setup: Callable, *,
                      sample_rows: int = 0, progress: bool | None = None,
                      n_threads: int | None = None):
    """``(setup, stats)``: the Gram statistics of all rows of ``source``.

    ``make_setup(n_states, n_inputs, sample=...)`` gives the
    :class:`~discrepancy.fitting.setup.FitSetup` once the first ``sample_rows`` rows (over
    trajectories, in order; at least the first chunk) have been read and validated:
    ``sample`` holds them as trajectories, so that choices made from the data (the
    default smoothing) see the same rows as an in-memory fit would. Every trajectory must
    have the layout of the first.
    """
    sample, trajectories = _prefetch(source, step, max(sample_rows, 1))
    layout = sample[0][0]
    setup = make_setup(layout.n, layout.r, sample=[_joined(chunks) for _, chunks, _ in sample])
    acc = BlockAccumulator(setup.transform, setup.new_statistics(), n_threads=n_threads,
                           names=setup.names)
    feeder = _RowFeeder(acc)
    with tqdm(total=source.n_samples, unit=" samples", unit_scale=True, desc="fit",
              disable=None if progress is None else not progress) as bar:
        held = acc.total.held_out    # forecast windows, kept as the rows go by
        for chunks in trajectories(layout):
            def counted(chunks=chunks):
                for chunk in chunks:
                    if held is not None:
                        held.add(chunk.t, chunk.x, chunk.u)
                    yield chunk
                    bar.update(chunk.n_rows)

            if held is not None:
                held.begin(acc.total.count)
            for rows in residual_rows(setup, counted()):
                feeder.add(*rows)
            feeder.end_trajectory()
    return setup, acc.total


def _prefetch(source: ChunkSource, step: float, budget: int):
    """Read (and validate) the first ``budget`` rows; returns ``(sample, trajectories)``.

    ``sample``: ``[(layout, chunks read, rest of that trajectory's chunks)]``;
    ``trajectories(layout)`` then yields every trajectory as an iterator of validated
    chunks, the prefetched ones first, so nothing is read twice.
    """
    it = enumerate(source.trajectories())
    sample, layout, rows = [], None, 0
    for k, items in it:
        stream = validated_chunks(items, k, step, layout)
        read = []
        for lay, chunk in stream:
            layout = lay
            read.append(chunk)
            rows += chunk.n_rows
            if rows >= budget:
                break
        if not read:
            raise ShapeError(f"trajectory {k} of x has no rows")
        sample.append((layout, read, stream))
        if rows >= budget:
            break
    if not sample:
        raise ShapeError("x holds no trajectories")

    def trajectories(layout):
        for _, read, rest in sample:
            yield _chain(read, (chunk for _, chunk in rest))
        for k, items in it:
            stream = validated_chunks(items, k, step, layout)
            first = next(stream, None)
            if first is None:
                raise ShapeError(f"trajectory {k} of x has no rows")
            yield _chain([first[1]], (chunk for _, chunk in stream))

    return sample, trajectories


def _joined(chunks: list[Chunk]) -> Trajectory:
    """The prefetched chunks of one trajectory as one Trajectory (for choices from data)."""
    def cat(field):
        parts = [getattr(c, field) for c in chunks]
        return None if parts[0] is None else np.concatenate(parts)
    return Trajectory(cat("t"), cat("x"), cat("u"), cat("x_dot"))


def _chain(first: list, rest):
    yield from first
    yield from rest


def chunk_statistics(make_setup: Callable, differentiation_method, x, *, t=None, u=None,
                     x_dot=None):
    """``(setup, stats)`` of chunked input ``x`` (see the module docstring).

    ``make_setup(n_states, n_inputs, sample=...)`` gives the set-up (a model passes its
    own) once the rows that ``differentiation_method`` chooses from are read
    (:func:`~discrepancy.fitting.setup.sample_rows`)."""
    if u is not None or x_dot is not None:
        raise ParameterError("with chunked x, give u and x_dot inside the chunks "
                             "(Chunk(x, u=..., x_dot=...)), not as separate arguments")
    return stream_statistics(as_source(x), step_of(t), make_setup,
                             sample_rows=sample_rows(differentiation_method))


def source_setup(make_setup: Callable, differentiation_method, source: ChunkSource,
                 step: float):
    """``make_setup`` from the layout and first rows of ``source`` (read, not fitted)."""
    sample, _ = _prefetch(source, step, max(sample_rows(differentiation_method), 1))
    layout = sample[0][0]
    return make_setup(layout.n, layout.r, sample=[_joined(chunks) for _, chunks, _ in sample])
