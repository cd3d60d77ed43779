"""Validation of measured data: the one place where user arrays are checked.

Every public entry point that takes whole trajectories calls :func:`as_trajectories`
(checks in :mod:`discrepancy.data.validation`), which turns ``x`` (one ``(m, n)`` array or
a list of them), ``t`` (a step or an array of times), ``u`` and ``x_dot`` into a list of
:class:`Trajectory` with float64 arrays, or raises a :mod:`discrepancy.errors` exception
naming the argument.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import DataError, ShapeError, describe
from .validation import check_array, check_finite, check_times, is_uniform  # noqa: F401

#: largest sample weight below which all weights are divided by it (only their ratios
#: matter; subnormal weights such as 5e-324 would make the weighted sums of squares 0)
TINY_WEIGHT = 1e-100


@dataclass(frozen=True)
class Trajectory:
    """One measured trajectory.

    Attributes:
        t: times, shape ``(m,)``, strictly increasing (s or the user's time unit).
        x: states, shape ``(m, n)``.
        u: inputs, shape ``(m, r)``, or ``None``.
        x_dot: measured state derivatives, shape ``(m, n)``, or ``None``.
        weight: non-negative weight of each sample in the regression, ``(m,)``, or ``None``.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray | None = None
    x_dot: np.ndarray | None = None
    weight: np.ndarray | None = None

    @property
    def n_samples(self) -> int:
        """Number of samples ``m``."""
        return self.x.shape[0]


def as_2d(name: str, a, *, n_rows: int | None = None, n_cols: int | None = None,
          allow_1d: bool = False) -> np.ndarray:
    """Float64 2-D array ``(samples, variables)``, checked (see :func:`check_array`)."""
    return check_array(name, a, n_rows=n_rows, n_cols=n_cols, allow_1d=allow_1d)


def as_times(name: str, t, m: int) -> np.ndarray:
    """Times of ``m`` samples from a positive step or a strictly increasing array."""
    return check_times(name, t, m)


def one_per_trajectory(name: str, value, k: int, *, broadcast: bool):
    """``value`` as a list of ``k`` items, one per trajectory: a list or tuple of that
    length as given, or (``broadcast``) one value repeated; ShapeError otherwise."""
    if isinstance(value, (list, tuple)):
        if len(value) != k:
            raise ShapeError(f"{name} must be a list of {k} items (one per trajectory of x); "
                             f"got {len(value)}")
        return list(value)
    if broadcast or k == 1:
        return [value] * k
    raise ShapeError(f"{name} must be a list of {k} arrays when x is a list of trajectories; "
                     f"got {describe(value)}")


def as_trajectories(x, t=None, u=None, x_dot=None, sample_weight=None, *,
                    x_name: str = "x") -> list[Trajectory]:
    """Validate data and return a list of trajectories.

    Args:
        x: states, ``(m, n)`` array or list of such arrays (several trajectories,
            never differentiated across their joins). All must have the same ``n``.
        t: time step (float > 0) or times ``(m,)``, or a list of those per trajectory
            (one step or one array of times is shared by every trajectory, as in PySINDy).
            ``None`` means a unit step.
        u: inputs ``(m, r)`` (or ``(m,)`` for one input), a list per trajectory, or one
            number (a constant input in every trajectory, as PySINDy broadcasts it).
        x_dot: measured derivatives ``(m, n)``, or a list per trajectory.
        sample_weight: weights of the samples in the regression: ``(m,)``, or a list per
            trajectory of arrays or numbers (a number weighs a whole trajectory).
        x_name: the argument's name in error messages (``"y"`` for measured outputs).
    """
    several = isinstance(x, (list, tuple))
    if is_number(u):
        u = [np.full(np.shape(xi)[:1], float(u)) for xi in (x if several else [x])]
        u = u if several else u[0]
    xs = list(x) if several else [x]
    if not xs:
        raise ShapeError(f"{x_name} must hold at least one trajectory; got an empty list")
    k = len(xs)
    if several:
        ts = one_per_trajectory("t", 1.0 if t is None else t, k,   # one array: shared,
                                broadcast=not isinstance(t, (list, tuple)))   # as in PySINDy
        us = one_per_trajectory("u", u, k, broadcast=u is None)
        xds = one_per_trajectory("x_dot", x_dot, k, broadcast=x_dot is None)
        ws = one_per_trajectory("sample_weight", sample_weight, k, broadcast=sample_weight is None)
    else:
        ts, us, xds, ws = [1.0 if t is None else t], [u], [x_dot], [sample_weight]
    out, n, r = [], None, None
    for i in range(k):
        tag = "" if k == 1 else f"[{i}]"
        xi = as_2d(f"{x_name}{tag}", xs[i], allow_1d=True)  # 1-D: one state, as in PySINDy
        if n is None:
            n = xi.shape[1]
        elif xi.shape[1] != n:
            raise ShapeError(f"every trajectory in {x_name} must have {n} columns like "
                             f"{x_name}[0]; {x_name}{tag} has shape {xi.shape}")
        m = xi.shape[0]
        if m < 2:
            raise ShapeError(f"{x_name}{tag} must have at least 2 samples; got shape "
                             f"{xi.shape}")
        ti = as_times(f"t{tag}", ts[i], m)
        ui = None if us[i] is None else as_2d(f"u{tag}", us[i], n_rows=m, allow_1d=True)
        if ui is not None:
            if r is None:
                r = ui.shape[1]
            elif ui.shape[1] != r:
                raise ShapeError(f"every u must have {r} input columns; u{tag} has {ui.shape}")
        if (ui is None) != (us[0] is None):
            raise ShapeError(f"u must be given for all trajectories or none; u{tag} differs")
        xdi = None if xds[i] is None else as_2d(f"x_dot{tag}", xds[i], n_rows=m, n_cols=n,
                                                allow_1d=True)
        out.append(Trajectory(ti, xi, ui, xdi, check_weight(f"sample_weight{tag}", ws[i], m)))
    if sample_weight is not None and not any(np.any(tr.weight > 0) for tr in out):
        raise DataError("sample_weight must have at least one positive weight; all are 0, "
                        "which leaves nothing to fit")
    if sample_weight is not None:
        top = max(float(tr.weight.max()) for tr in out)
        if top < TINY_WEIGHT:     # relative weights: rescaled, or the Gram sums underflow
            out = [dataclasses.replace(tr, weight=tr.weight / top) for tr in out]
    return out


def is_number(value) -> bool:
    """One real number (not a bool, not an array)."""
    import numbers

    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def check_weight(name: str, weight, m: int, *, where: str | None = None,
                 row_offset: int = 0) -> np.ndarray | None:
    """Sample weights ``(m,)`` from ``None``, a number (every sample) or an array."""
    if weight is None:
        return None
    w = check_array(name, np.full(m, weight) if np.ndim(weight) == 0 else weight, ndim=1,
                    n_rows=m, where=where, row_offset=row_offset)
    if np.any(w < 0):
        raise DataError(f"{where + ': ' if where else ''}{name} must be >= 0; found "
                        f"{w[np.argmax(w < 0)]} at row {row_offset + int(np.argmax(w < 0))}")
    return w
