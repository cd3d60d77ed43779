"""Regression rows of discrete-time models, maps ``x[k+1] = f_m(x[k], u[k]) + g(x[k], u[k])``.

The regression target of sample ``k`` is ``x[k+1] - f_m(x[k], u[k])``; the last sample of
a trajectory has no successor and gives no row. For chunked fits the successor is the one
sample the next chunk carries over, so streamed and in-memory rows are the same.
"""
from __future__ import annotations

import numpy as np

from ..differentiation.base import Differentiator
from ..errors import ShapeError


class NextSample(Differentiator):
    """Stands in for a differentiation method in discrete-time fits: it pairs each sample
    with the next (``halo`` 1 on the right, so chunk stitching keeps the successor)."""

    @property
    def halo(self) -> int:
        return 1

    @property
    def min_samples(self) -> int:
        return 2

    def _compute(self, x, t):
        raise NotImplementedError("discrete-time rows come from FitSetup.rows")


def discrete_rows(setup, trajectory):
    """``(z, y, x_next)`` of a trajectory for a map: ``m - 1`` rows, or ``m`` rows when the
    successors are given as ``x_dot`` (PySINDy's ``fit(x[:-1], x_dot=x[1:])``)."""
    x, u = trajectory.x, trajectory.u
    if trajectory.x_dot is not None:
        y = trajectory.x_dot - setup.prior(x, u)
        return (x if u is None else np.hstack([x, u])), y, trajectory.x_dot
    if len(x) < 2:
        raise ShapeError("a discrete-time trajectory needs at least 2 samples")
    u_now = None if u is None else u[:-1]
    y = x[1:] - setup.prior(x[:-1], u_now)
    z = x[:-1] if u is None else np.hstack([x[:-1], u_now])
    return z, y, x[1:]
