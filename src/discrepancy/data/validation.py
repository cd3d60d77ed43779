"""The one place where user arrays are checked, for in-memory, chunked and Dask data alike.

Every path that takes data (``fit`` on arrays, chunk streams, Dask blocks, file loaders,
``predict``/``simulate``) calls :func:`check_array` and :func:`check_times`, so a bad value
is reported the same way wherever it comes from: the argument's name, where it is (chunk,
file rows), its row and column in the whole trajectory, what was expected and what was given.
"""
from __future__ import annotations

import numpy as np

from ..errors import DataError, ShapeError, describe

__all__ = ["as_float_array", "check_array", "check_times", "check_vector", "is_uniform"]


def _place(where: str | None) -> str:
    return f"{where}: " if where else ""


def as_float_array(name: str, a, where: str | None = None) -> np.ndarray:
    """Float64 array of any shape from ``a``: ShapeError for non-numbers, DataError for
    complex or date values (no check of finiteness or shape)."""
    if isinstance(a, (str, bytes)):
        raise ShapeError(f"{_place(where)}{name} must be a numeric array; got {describe(a)}")
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError) as e:
        raise ShapeError(f"{_place(where)}{name} must be a numeric array; got {describe(a)} "
                         f"({e})") from None
    if np.iscomplexobj(arr):
        raise DataError(f"{_place(where)}{name} must be real; got complex values (the "
                        "imaginary part would be dropped)")
    if arr.dtype.kind in "mM":
        raise DataError(f"{_place(where)}{name} must be plain numbers; got {arr.dtype} values "
                        "(convert dates to seconds first: (t - t[0]) / np.timedelta64(1, 's'))")
    if arr.dtype.kind not in "biuf":
        try:
            arr = arr.astype(float)
        except (TypeError, ValueError) as e:
            raise ShapeError(f"{_place(where)}{name} must be a numeric array; got "
                             f"{describe(a)} of {arr.dtype} ({e})") from None
    return np.asarray(arr, dtype=float)


def check_finite(name: str, a: np.ndarray, *, where: str | None = None,
                 row_offset: int = 0) -> None:
    """Raise DataError naming the first non-finite entry of ``a``: its row (in a chunk, also
    its row in the whole trajectory, counted from ``row_offset``) and column."""
    bad = ~np.isfinite(a)
    if not bad.any():
        return
    index = [int(i) for i in np.argwhere(bad)[0]]
    if not index:
        at = ""
    elif where:
        col = f", column {index[1]}" if len(index) > 1 else ""
        at = f" at row {index[0]} of the chunk (row {row_offset + index[0]} of the trajectory{col})"
    else:
        at = f" at row {index[0]}" + (f", column {index[1]}" if len(index) > 1 else "")
    raise DataError(f"{_place(where)}{name} must be finite; found {a[tuple(index)]}{at} "
                    f"({int(bad.sum())} non-finite values{' in this chunk' if where else ''}). "
                    "Clean or drop those rows first")


def check_array(name: str, a, *, n_rows: int | None = None, n_cols: int | None = None,
                allow_1d: bool = False, ndim: int = 2, min_cols: int = 1,
                where: str | None = None, row_offset: int = 0) -> np.ndarray:
    """Float64 array of ``ndim`` dimensions (2: samples x variables) from ``a``, checked.

    Args:
        name: the argument's name, used in messages.
        n_rows, n_cols: required row/column counts (``None``: any).
        allow_1d: a 1-D array is one column (``(m,)`` -> ``(m, 1)``).
        ndim: 2 for tables, 1 for vectors such as times.
        min_cols: fewest columns accepted (an ``(m, 0)`` array is almost always a mistake).
        where, row_offset: where the rows come from (chunk, file) and the trajectory row of
            the first one, for messages.

    Raises:
        ShapeError: non-numeric input or wrong shapes.
        DataError: complex, date or non-finite values.
    """
    arr = as_float_array(name, a, where)
    if ndim == 2 and arr.ndim == 1 and allow_1d:
        arr = arr[:, None]
    if arr.ndim != ndim:
        hint = " (use a.reshape(-1, 1) for a single variable)" if ndim == 2 and arr.ndim == 1 \
            else ""
        shape = "1-D" if ndim == 1 else "2-D (samples, variables)"
        raise ShapeError(f"{_place(where)}{name} must be {shape}; got shape {arr.shape}{hint}")
    if n_rows is not None and arr.shape[0] != n_rows:
        raise ShapeError(f"{_place(where)}{name} must have {n_rows} rows (one per sample); got "
                         f"shape {arr.shape}")
    if ndim == 2:
        if n_cols is not None and arr.shape[1] != n_cols:
            raise ShapeError(f"{_place(where)}{name} must have {n_cols} columns; got shape "
                             f"{arr.shape}")
        if arr.shape[1] < min_cols:
            raise ShapeError(f"{_place(where)}{name} must have at least {min_cols} column(s); "
                             f"got shape {arr.shape}")
    check_finite(name, arr, where=where, row_offset=row_offset)
    return arr


def check_vector(name: str, a, size: int, *, where: str | None = None) -> np.ndarray:
    """``size`` finite numbers ``(size,)`` from ``a`` (any shape holding that many, e.g. a
    state ``(n,)`` or ``(1, n)``)."""
    arr = as_float_array(name, a, where).reshape(-1)
    if arr.shape != (size,):
        raise ShapeError(f"{_place(where)}{name} must be {size} numbers; got {describe(a)}")
    check_finite(name, arr, where=where)
    return arr


def check_times(name: str, t, m: int, *, where: str | None = None,
                after: float | None = None, row_offset: int = 0) -> np.ndarray:
    """Times ``(m,)`` from a positive step (a number) or a strictly increasing 1-D array.

    ``after``: the last time before these rows (a previous chunk's), which they must exceed.
    """
    if isinstance(t, (str, bytes, bool, np.bool_)) or (np.ndim(t) == 0 and
                                                       not _is_real_number(t)):
        if np.ndim(t) == 0 and np.asarray(t).dtype.kind in "mM":
            as_float_array(name, t, where)
        raise DataError(f"{_place(where)}{name} must be a positive time step (a number) or an "
                        f"array of {m} times; got {describe(t)}")
    if np.ndim(t) == 0:
        dt = float(t)
        if not np.isfinite(dt) or dt <= 0:
            raise DataError(f"{_place(where)}{name} as a time step must be a positive finite "
                            f"number; got {dt}")
        times = (np.arange(m) + row_offset) * dt
        if m and not np.isfinite(times[-1]):
            raise DataError(f"{_place(where)}{name} as a time step of {dt:g} puts the last of "
                            f"{m} samples beyond float range; give a smaller step")
        return times
    times = check_array(name, t, ndim=1, where=where, row_offset=row_offset)
    if times.shape[0] != m:
        raise ShapeError(f"{_place(where)}{name} must be a step or a 1-D array of {m} times (one "
                         f"per row of x); got shape {times.shape}")
    full = times if after is None else np.r_[after, times]
    steps = np.diff(full)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0))  # full[i + 1] does not come after full[i]
        row = row_offset + i + (1 if after is None else 0)
        raise DataError(f"{_place(where)}{name} must be strictly increasing (also across "
                        f"chunks); {name}[{row}] = {float(full[i + 1])!r} follows "
                        f"{name}[{row - 1}] = {float(full[i])!r}")
    return times


def _is_real_number(value) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return False
    arr = np.asarray(value)
    return arr.dtype.kind in "iuf"


def is_uniform(t: np.ndarray, rtol: float = 1e-6) -> bool:
    """True when the steps of ``t`` are equal to within ``rtol`` of the mean step."""
    steps = np.diff(t)
    return bool(np.all(np.abs(steps - steps.mean()) <= rtol * abs(steps.mean())))
