"""Fields larger than memory: streamed from zarr or HDF5 in time chunks.

A :class:`FieldSource` names arrays ``(m, *grid.shape[, n])`` (time first) on disk or any
array-like that slices lazily (``h5py`` and ``zarr`` datasets, ``np.memmap``). A fit reads
``chunk`` snapshots at a time plus ``halo`` on each side (what a derivative window or a
test function needs), keeps the rows of the chunk's own snapshots, and adds their Gram
statistics; rows at a run's true ends are those of the in-memory fit, so the sums, and the
model, equal the in-memory ones (to rounding). Memory is a few chunks of the field and the
jet of one chunk, whatever the run's length. Choices made from the data (smoothing, test
functions) look at the first 512 snapshots (over runs in order), as in memory.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .._optional import require
from ..constraints import Integral, Interval, validate_params
from ..data.fields import FieldRun, Grid, field_array
from ..data.validation import check_times
from ..errors import MissingFileError, ParameterError, ShapeError, UnknownNameError, describe
from .resolve import SAMPLE_SNAPSHOTS

#: bytes of field data per chunk when ``chunk_size`` is not given
CHUNK_BYTES = 32 * 2**20


class FieldSource:
    """Runs of fields read lazily in time chunks (see the module docstring).

    Args:
        arrays: one array-like ``(m, *grid.shape[, n])`` or a list (one per run), or
            ``(path, dataset)`` pairs: HDF5 files (``.h5``, ``.hdf5``) or zarr stores.
        grid: the :class:`~discrepancy.Grid`.
        dt: time step of every run.
        chunk_size: snapshots per chunk (default: about 32 MB of fields).
    """

    def __init__(self, arrays, *, grid: Grid, dt: float, chunk_size: int | None = None):
        if not isinstance(grid, Grid):
            raise ParameterError(f"grid must be a discrepancy.Grid; got {describe(grid)}")
        validate_params("FieldSource", {"chunk_size": chunk_size},
                        {"chunk_size": [None, Interval(Integral, 1)]})
        self.grid, self.dt = grid, float(check_times("dt", dt, 2)[1])
        items = arrays if isinstance(arrays, list) else [arrays]
        if not items:
            raise ShapeError("FieldSource needs at least one run")
        self.items = items
        shapes = [self._shape(i, a) for i, a in enumerate(items)]
        self.n_fields = shapes[0][1]
        if any(s[1] != self.n_fields for s in shapes):
            raise ShapeError(f"every run must hold {self.n_fields} fields like the first")
        self.lengths = [s[0] for s in shapes]
        per = grid.size * self.n_fields * 8
        self.chunk_size = int(chunk_size or max(1, CHUNK_BYTES // per))

    @property
    def n_snapshots(self) -> int:
        """Snapshots (time samples) over all runs of the source."""
        return sum(self.lengths)

    def _shape(self, i, item) -> tuple[int, int]:
        with _opened(item) as a:
            shape = tuple(getattr(a, "shape", ()))
        spatial = self.grid.shape
        if len(shape) == self.grid.ndim + 1 and shape[1:] == spatial:
            return shape[0], 1
        if len(shape) == self.grid.ndim + 2 and shape[1:-1] == spatial:
            return shape[0], shape[-1]
        raise ShapeError(f"run {i} of the FieldSource must be (time, "
                         f"{', '.join(map(str, spatial))}[, fields]); got shape {shape}")

    def read(self, run: int, start: int, stop: int) -> FieldRun:
        """Snapshots ``start:stop`` of run ``run``, validated, as a FieldRun."""
        with _opened(self.items[run]) as a:
            block = np.asarray(a[start:stop], dtype=float)
        where = f"run {run} snapshots {start}..{stop - 1}"
        u = field_array("u", block, self.grid, n_fields=self.n_fields, where=where,
                        row_offset=start)
        return FieldRun(np.arange(start, stop) * self.dt, u, None, self.grid)


class _opened:
    """Context manager: the array of an item (opening and closing a file when it is one)."""

    def __init__(self, item):
        self.item, self.handle = item, None

    def __enter__(self):
        if not (isinstance(self.item, tuple) and len(self.item) == 2):
            return self.item
        path, name = Path(self.item[0]), self.item[1]
        if not path.exists():
            raise MissingFileError(f"field file {str(path)!r} does not exist")
        if path.suffix in (".h5", ".hdf5"):
            self.handle = require("h5py", purpose="reading HDF5 fields").File(path, "r")
        else:
            self.handle = require("zarr", purpose="reading zarr fields").open(str(path),
                                                                                mode="r")
        try:
            return self.handle[name]
        except KeyError:
            raise UnknownNameError(f"{path.name}: no dataset {name!r}") from None

    def __exit__(self, *exc):
        close = getattr(self.handle, "close", None)
        if close:
            close()


def stream_statistics(model, source: FieldSource, *, progress=None):
    """``(setup, stats)``: the Gram statistics of every snapshot of ``source``."""
    from tqdm.auto import tqdm

    sample, budget = [], SAMPLE_SNAPSHOTS
    for run, m in enumerate(source.lengths):
        if budget <= 0:
            break
        sample.append(source.read(run, 0, min(m, budget)))
        budget -= min(m, budget)
    setup = model.make_setup(source.n_fields, 0, source.grid, sample=sample,
                             lengths=source.lengths)
    stats, halo = setup.new_statistics(), setup.halo
    if halo is None:
        raise ParameterError(f"{setup.time_methods[0]!r} is a global method; streamed fits "
                             "need a local one (SavitzkyGolay, FiniteDifference, the weak form)")
    chunk = max(source.chunk_size, 2 * halo + 1)
    with tqdm(total=source.n_snapshots, unit=" snapshots", desc="fit",
              disable=None if progress is None else not progress) as bar:
        for run, m in enumerate(source.lengths):
            if m < setup.min_samples:
                raise ShapeError(f"run {run} has {m} snapshots; the time method needs "
                                 f"{setup.min_samples}")
            for a in range(0, m, chunk):
                b = min(m, a + chunk)
                lo, hi = max(0, a - halo), min(m, b + halo)
                lo = max(0, min(lo, hi - setup.min_samples))  # a short tail reads more
                piece = source.read(run, lo, hi)
                setup.statistics(piece, into=stats, keep=slice(a - lo, b - lo))
                bar.update(b - a)
    return setup, stats
