"""Cubic smoothing spline with the smoothing chosen by GCV (scipy), any sampling times."""
from __future__ import annotations

import numpy as np

from ..constraints import Interval, Real
from .base import Differentiator, register


@register("smoothing_spline")
class SmoothingSpline(Differentiator):
    """Cubic smoothing spline per state (``scipy.interpolate.make_smoothing_spline``).

    Args:
        lam: the spline's roughness penalty; ``None`` (default) lets scipy choose it per
            state by generalized cross-validation.
        smooth: evaluate Θ on the spline (True) or on the measured x.

    Accepts non-uniform ``t``. A global method (every value depends on the whole record),
    so it cannot be applied chunk by chunk.
    """

    _parameter_constraints = {"lam": [None, Interval(Real, 0, None)], "smooth": [bool]}

    def __init__(self, lam: float | None = None, *, smooth: bool = True):
        self.lam = lam
        self.smooth = smooth

    @property
    def min_samples(self) -> int:
        return 5

    def _compute(self, x, t):
        from scipy.interpolate import make_smoothing_spline

        smooth, x_dot = np.empty_like(x), np.empty_like(x)
        for j in range(x.shape[1]):
            spline = make_smoothing_spline(t, x[:, j], lam=self.lam)
            smooth[:, j] = spline(t) if self.smooth else x[:, j]
            x_dot[:, j] = spline.derivative()(t)
        return smooth, x_dot
