"""Spatiotemporal data: fields sampled on uniform 1-D or 2-D grids, checked once.

A *run* is one recording of ``n`` fields on a grid: an array ``(m, *grid.shape, n)`` with
time along axis 0 (``(m, *grid.shape)`` for a single field), its times ``t`` (a step or
``(m,)`` strictly increasing, uniform) and optional inputs: fields ``(m, *grid.shape, r)``
or signals ``(m, r)`` that are the same everywhere. Every entry point that takes fields
calls :func:`as_field_runs`, which names the argument, the run and the position of any
problem, exactly as :func:`~discrepancy.data.trajectory.as_trajectories` does for
trajectories. PySINDy stores fields as ``(x, t, n)``: ``np.moveaxis(u, -2, 0)`` converts
its 1-D layout to this one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DataError, ParameterError, ShapeError, describe
from .validation import as_float_array, check_finite, check_times, is_uniform

__all__ = ["FieldRun", "Grid", "as_field_runs"]

#: coordinate names used when none are given, one per spatial axis
DEFAULT_COORDINATES = ("x", "y", "z")
#: grids of more spatial axes are refused (derivative libraries grow combinatorially)
MAX_AXES = 3


class Grid:
    """A uniform tensor grid in space, periodic or not along each axis.

    Args:
        *coordinates: one 1-D array of equally spaced, increasing positions per spatial
            axis (length units of the user). On a periodic axis the last point is NOT the
            first one repeated: the period is ``len(x) * dx`` (``np.linspace(0, L, n,
            endpoint=False)``).
        periodic: one bool for every axis, or one per axis.
        names: coordinate names, single lowercase letters (default ``x``, ``y``, ``z``);
            derivative variables are named after them: ``u_x``, ``u_xy``.

    Attributes:
        shape: points per axis; spacing: step per axis; period: ``n * dx`` per axis;
        size: points per snapshot.
    """

    def __init__(self, *coordinates, periodic=False, names=None):
        if not 1 <= len(coordinates) <= MAX_AXES:
            raise ShapeError(f"Grid takes 1 to {MAX_AXES} coordinate arrays (one per spatial "
                             f"axis); got {len(coordinates)}")
        axes = tuple(_axis(f"coordinates[{i}]", c) for i, c in enumerate(coordinates))
        flags = (periodic,) * len(axes) if np.ndim(periodic) == 0 else tuple(periodic)
        if len(flags) != len(axes) or not all(isinstance(f, (bool, np.bool_)) for f in flags):
            raise ParameterError(f"Grid: periodic must be True/False or one bool per axis "
                                 f"({len(axes)}); got {describe(periodic)}")
        names = DEFAULT_COORDINATES[:len(axes)] if names is None else tuple(names)
        if len(names) != len(axes) or len(set(names)) != len(names) or not all(
                isinstance(n, str) and len(n) == 1 and n.isalpha() and n.islower()
                for n in names) or "t" in names:
            raise ParameterError(f"Grid: names must be {len(axes)} distinct single lowercase "
                                 f"letters other than 't' (derivatives are named u_xy); got "
                                 f"{names!r}")
        self.coordinates, self.periodic, self.names = axes, tuple(bool(f) for f in flags), names

    @property
    def ndim(self) -> int:
        """Number of spatial axes (1 to 3)."""
        return len(self.coordinates)

    @property
    def shape(self) -> tuple[int, ...]:
        """Points per axis, ``(len(x), len(y), ...)``: the spatial part of a field's shape."""
        return tuple(len(c) for c in self.coordinates)

    @property
    def size(self) -> int:
        """Points per snapshot: the product of :attr:`shape`."""
        return int(np.prod(self.shape))

    @property
    def spacing(self) -> tuple[float, ...]:
        """Step between neighbouring points per axis, in the length units of the coordinates."""
        return tuple(float((c[-1] - c[0]) / (len(c) - 1)) for c in self.coordinates)

    @property
    def period(self) -> tuple[float, ...]:
        """``len(x) * dx`` per axis: the length after which a periodic axis wraps around (in
        length units; defined on every axis, meaningful on the periodic ones)."""
        return tuple(len(c) * h for c, h in zip(self.coordinates, self.spacing, strict=True))

    def mesh(self) -> tuple[np.ndarray, ...]:
        """Coordinate arrays broadcast to ``shape`` (``np.meshgrid(..., indexing="ij")``)."""
        return tuple(np.meshgrid(*self.coordinates, indexing="ij"))

    def __eq__(self, other) -> bool:
        return isinstance(other, Grid) and self.periodic == other.periodic and \
            self.names == other.names and self.shape == other.shape and all(
                np.array_equal(a, b) for a, b in zip(self.coordinates, other.coordinates,
                                                     strict=True))

    def __hash__(self):
        return hash((self.shape, self.periodic, self.names))

    def __repr__(self) -> str:
        axes = ", ".join(f"{n}: {len(c)} points, step {h:.4g}{' periodic' if p else ''}"
                         for n, c, h, p in zip(self.names, self.coordinates, self.spacing,
                                               self.periodic, strict=True))
        return f"Grid({axes})"


def _axis(name: str, c) -> np.ndarray:
    c = as_float_array(name, c)
    if c.ndim != 1 or c.shape[0] < 3:
        raise ShapeError(f"Grid: {name} must be a 1-D array of at least 3 positions; got "
                         f"{describe(c)}")
    check_finite(name, c)
    if np.any(np.diff(c) <= 0):
        raise DataError(f"Grid: {name} must be strictly increasing")
    if not is_uniform(c):
        steps = np.diff(c)
        raise DataError(f"Grid: {name} must be equally spaced (uniform grids only); its steps "
                        f"range over [{steps.min():.6g}, {steps.max():.6g}]")
    return c


@dataclass(frozen=True)
class FieldRun:
    """One validated run.

    Attributes:
        t: times ``(m,)``, uniform; u: fields ``(m, *grid.shape, n)``;
        inputs: ``(m, *grid.shape, r)`` (signals are broadcast over the grid) or ``None``;
        grid: the :class:`Grid`.
    """

    t: np.ndarray
    u: np.ndarray
    inputs: np.ndarray | None
    grid: Grid

    @property
    def n_samples(self) -> int:
        """Number of snapshots ``m`` (the length of the time axis)."""
        return self.u.shape[0]

    @property
    def n_fields(self) -> int:
        """Number of fields ``n`` (the last axis of ``u``)."""
        return self.u.shape[-1]


def field_array(name: str, u, grid: Grid, *, n_fields: int | None = None,
                where: str | None = None, min_samples: int = 1,
                row_offset: int = 0) -> np.ndarray:
    """``(m, *grid.shape, n)`` float64 from ``(m, *grid.shape)`` (one field) or
    ``(m, *grid.shape, n)``, checked: shape against the grid, finite values (``row_offset``:
    the run's time row of ``u[0]``, for messages about a chunk)."""
    place = f"{where}: " if where else ""
    a = as_float_array(name, u, where)
    spatial = grid.shape
    if a.ndim == grid.ndim + 1 and a.shape[1:] == spatial:
        a = a[..., None]
    if a.ndim != grid.ndim + 2 or a.shape[1:-1] != spatial or a.shape[-1] < 1:
        raise ShapeError(f"{place}{name} must be (time, {', '.join(map(str, spatial))}) for one "
                         f"field or (time, {', '.join(map(str, spatial))}, fields) on this "
                         f"grid (time first); got shape {a.shape}")
    if n_fields is not None and a.shape[-1] != n_fields:
        raise ShapeError(f"{place}{name} must hold {n_fields} fields (last axis); got shape "
                         f"{a.shape}")
    if a.shape[0] < min_samples:
        raise ShapeError(f"{place}{name} must have at least {min_samples} time samples; got "
                         f"shape {a.shape}")
    if not np.all(np.isfinite(a)):
        index = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise DataError(f"{place}{name} must be finite; found {a[index]} at time row "
                        f"{row_offset + index[0]}, grid point {index[1:-1]}, field {index[-1]} "
                        f"({int((~np.isfinite(a)).sum())} non-finite values)")
    return a


def input_array(name: str, v, grid: Grid, m: int, r: int | None) -> np.ndarray:
    """Inputs as ``(m, *grid.shape, r)``: input fields, or signals ``(m,)``/``(m, r)`` that are
    broadcast over the grid (an array shaped like a field is a field)."""
    a = as_float_array(name, v)
    is_field = a.ndim >= grid.ndim + 1 and a.shape[1:grid.ndim + 1] == grid.shape
    if not is_field and a.ndim in (1, 2):
        signal = a.reshape(a.shape[0], -1)
        check_finite(name, signal)
        a = np.broadcast_to(signal.reshape(a.shape[0], *(1,) * grid.ndim, -1),
                            (a.shape[0], *grid.shape, signal.shape[1]))
    else:
        a = field_array(name, a, grid)
    if a.shape[0] != m:
        raise ShapeError(f"{name} must have {m} time rows like the fields; got shape {a.shape}")
    if r is not None and a.shape[-1] != r:
        raise ShapeError(f"every run's inputs must have {r} columns; {name} has {a.shape[-1]}")
    return a


def _per_run(name: str, value, k: int, *, scalar_ok: bool) -> list:
    """One ``value`` per run: a list of ``k``, or ``None`` / a number shared by all."""
    if isinstance(value, (list, tuple)):
        if len(value) != k:
            raise ShapeError(f"{name} must be a list of {k} items (one per run of u); got "
                             f"{len(value)}")
        return list(value)
    if value is None or (scalar_ok and np.ndim(value) == 0):
        return [value] * k
    raise ShapeError(f"{name} must be a list of {k} items when u is a list of runs; got "
                     f"{describe(value)}")


def as_field_runs(u, t, grid, inputs=None, *, name: str = "u",
                  min_samples: int = 3) -> list[FieldRun]:
    """Validate fields and return a list of :class:`FieldRun` (see the module docstring).

    Args:
        u: fields of one run, or a list of runs (never differentiated across runs); every
            run must hold the same number of fields.
        t: time step (a number), times ``(m,)`` (uniform), or a list per run.
        grid: the :class:`Grid` every run is sampled on.
        inputs: ``None``, or per run input fields ``(m, *grid.shape, r)`` or signals
            ``(m, r)``; a list when ``u`` is.
    """
    if not isinstance(grid, Grid):
        raise ParameterError(f"grid must be a discrepancy.Grid (e.g. Grid(x, periodic=True)); "
                             f"got {describe(grid)}")
    several = isinstance(u, (list, tuple))
    runs = list(u) if several else [u]
    if not runs:
        raise ShapeError(f"{name} must hold at least one run; got an empty list")
    k = len(runs)
    ts = _per_run("t", 1.0 if t is None else t, k, scalar_ok=True) if several else [t]
    vs = _per_run("inputs", inputs, k, scalar_ok=False) if several else [inputs]
    out, n, r = [], None, None
    for i, (ui, ti, vi) in enumerate(zip(runs, ts, vs, strict=True)):
        tag = f"{name}[{i}]" if several else name
        a = field_array(tag, ui, grid, n_fields=n, min_samples=min_samples)
        n = a.shape[-1]
        label = f"t[{i}]" if several else "t"
        times = check_times(label, 1.0 if ti is None else ti, a.shape[0])
        if not is_uniform(times):
            raise DataError(f"{label} must be equally spaced (fields "
                            "are differentiated and integrated on a uniform time grid)")
        if (vi is None) != (vs[0] is None):
            raise ShapeError(f"inputs must be given for all runs or none; run {i} differs")
        v = None if vi is None else input_array(f"inputs[{i}]" if several else "inputs", vi,
                                                 grid, a.shape[0], r)
        r = None if v is None else v.shape[-1]
        out.append(FieldRun(times, a, v, grid))
    return out
