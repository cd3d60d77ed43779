"""Concrete differentiation methods.

Finite differences use ``numpy.gradient``, Savitzky–Golay uses
``scipy.signal.savgol_filter``, and the global smoothers (spline, trend
filtering, Kalman) come from the ``derivative`` package; nothing here
re-implements them.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .base import Differentiator, register


@register("finite_difference")
class FiniteDifference(Differentiator):
    """Second-order centred differences (``numpy.gradient``), one-sided of second order at the
    ends. Accepts non-uniform ``t``; error O(dt²). No smoothing."""

    @property
    def halo(self) -> int:
        return 1

    def _compute(self, x, t):
        return x, np.gradient(x, t, axis=0, edge_order=2)


@register("savitzky_golay")
class SavitzkyGolay(Differentiator):
    """Savitzky–Golay smoothing and differentiation (the paper's choice).

    Args:
        window_length: odd number of samples in the local polynomial fit.
        polyorder: degree of the local polynomial, below ``window_length``.
        smooth: if True (default, as in the paper) Θ is evaluated on the smoothed x.

    Needs uniform ``t``. Ends use the polynomial fitted to the first/last window.
    """

    uniform_only = True

    def __init__(self, window_length: int = 21, polyorder: int = 3, *, smooth: bool = True):
        self.window_length = window_length
        self.polyorder = polyorder
        self.smooth = smooth

    def _check(self):
        w, p = self.window_length, self.polyorder
        if not isinstance(w, (int, np.integer)) or w < 3 or w % 2 == 0:
            raise ParameterError(f"window_length must be an odd integer >= 3; got {w!r}")
        if not isinstance(p, (int, np.integer)) or not 1 <= p < w:
            raise ParameterError(f"polyorder must be an integer in [1, window_length); got {p!r}")

    @property
    def min_samples(self) -> int:
        self._check()
        return int(self.window_length)

    @property
    def halo(self) -> int:
        return int(self.window_length) // 2

    def _compute(self, x, t):
        from scipy.signal import savgol_filter  # 1 s to import: only when used

        dt = (t[-1] - t[0]) / (len(t) - 1)
        kw = dict(window_length=self.window_length, polyorder=self.polyorder, axis=0, mode="interp")
        x_dot = savgol_filter(x, deriv=1, delta=dt, **kw)
        return (savgol_filter(x, **kw) if self.smooth else x), x_dot


class _DerivativePackage(Differentiator):
    """Adapter for a method of the ``derivative`` package (``derivative.methods``)."""

    _kind: str

    def _method(self):
        from derivative import methods
        return methods[self._kind](**self._kwargs())

    def _kwargs(self) -> dict:
        return {k: v for k, v in vars(self).items() if not k.startswith("_") and k != "smooth"}

    def _compute(self, x, t):
        method = self._method()
        x_dot = method.d(x, t, axis=0)
        x_smooth = method.x(x, t, axis=0) if getattr(self, "smooth", False) else x
        return np.asarray(x_smooth, float), np.asarray(x_dot, float)


@register("spline")
class Spline(_DerivativePackage):
    """Smoothing spline (``derivative`` kind ``spline``, scipy ``splrep``); non-uniform t accepted.

    Args:
        s: smoothing condition of ``splrep`` (sum of squared residuals allowed);
            about ``m * sigma**2`` for noise of standard deviation sigma.
        order: spline degree, 1..5.
    """

    _kind = "spline"

    def __init__(self, s: float = 0.0, order: int = 3, *, smooth: bool = True):
        if s < 0:
            raise ParameterError(f"s (spline smoothing) must be >= 0; got {s}")
        self.s = s
        self.order = order
        self.smooth = smooth

    @property
    def min_samples(self) -> int:
        return self.order + 2


@register("trend_filtered")
class TrendFiltered(_DerivativePackage):
    """Total-variation regularised derivative (``derivative`` kind ``trend_filtered``).

    Args:
        order: polynomial order of the piecewise derivative (0 = piecewise constant).
        alpha: weight of the l1 penalty on the (order+1)-th difference.
        max_iter: iterations of the Lasso solver.
    """

    _kind = "trend_filtered"
    uniform_only = True

    def __init__(self, order: int = 0, alpha: float = 1e-2, max_iter: int = 10000):
        self.order = order
        self.alpha = alpha
        self.max_iter = max_iter


@register("kalman")
class Kalman(_DerivativePackage):
    """Kalman smoother with a Brownian derivative (``derivative`` kind ``kalman``).

    Args:
        alpha: ratio of measurement noise variance to process variance; larger is smoother.

    The package solves a dense ``2m x 2m`` system, so trajectories longer than
    ``max_samples`` are refused rather than left to run for hours.
    """

    _kind = "kalman"
    max_samples = 4000

    def __init__(self, alpha: float = 1.0, *, smooth: bool = True):
        self.alpha = alpha
        self.smooth = smooth

    def _compute(self, x, t):
        if len(t) > self.max_samples:
            raise ParameterError(f"Kalman smoothing of {len(t)} samples would need a dense "
                                 f"{2 * len(t)}-square solve; split the trajectory into pieces "
                                 f"of at most {self.max_samples} samples or use SavitzkyGolay")
        return super()._compute(x, t)
