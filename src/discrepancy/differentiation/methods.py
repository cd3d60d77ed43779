"""Concrete differentiation methods.

Savitzky–Golay uses
``scipy.signal.savgol_filter``, and the global smoothers (spline, trend
filtering, Kalman) come from the ``derivative`` package; nothing here
re-implements them.
"""
from __future__ import annotations

import numpy as np

from ..constraints import Integral, Interval, Predicate, Real
from ..errors import ConvergenceError, ParameterError
from .base import Differentiator, register
from .savgol import savgol

#: highest Savitzky-Golay degree: filters cost O(window x degree^2) to build (degree 999 of a
#: 1001-sample window took over 20 s) and degrees beyond a few tens add nothing measurable
MAX_POLYORDER = 30
#: an odd window of at least 3 samples (Savitzky-Golay smoothers)
ODD_WINDOW = Predicate(lambda w: isinstance(w, (int, np.integer)) and not isinstance(w, bool)
                       and w >= 3 and w % 2 == 1, "an odd integer >= 3")


@register("savitzky_golay")
class SavitzkyGolay(Differentiator):
    """Savitzky–Golay smoothing and differentiation (the paper's choice).

    Args:
        window_length: odd number of samples in the local polynomial fit, or one per
            state (a list).
        polyorder: degree of the local polynomial, below every window length.
        smooth: if True (default, as in the paper) Θ is evaluated on the smoothed x.

    Needs uniform ``t``. Ends use the polynomial fitted to the first/last window. The
    filters are computed by :mod:`discrepancy.differentiation.savgol` (accurate for long
    windows and high degrees, where scipy's are not).
    """

    uniform_only = True
    _parameter_constraints = {
        "window_length": [ODD_WINDOW, Predicate(
            lambda v: isinstance(v, (list, tuple)) and len(v) > 0 and all(
                ODD_WINDOW.is_satisfied_by(w) for w in v), "a list of odd integers >= 3")],
        "polyorder": [Interval(Integral, 1, MAX_POLYORDER)], "smooth": [bool]}

    def __init__(self, window_length: int = 21, polyorder: int = 3, *, smooth: bool = True):
        self.window_length = window_length
        self.polyorder = polyorder
        self.smooth = smooth

    def _windows(self, n: int | None = None) -> list[int]:
        w = self.window_length
        windows = [int(v) for v in w] if isinstance(w, (list, tuple)) else [int(w)]
        if n is not None and len(windows) not in (1, n):
            raise ParameterError(f"SavitzkyGolay: window_length has {len(windows)} values; x "
                                 f"has {n} columns (give one window, or one per column)")
        return windows * n if n is not None and len(windows) == 1 else windows

    def _check_params(self):
        if self.polyorder >= min(self._windows()):
            raise ParameterError(f"SavitzkyGolay: polyorder must be below window_length "
                                 f"({self.window_length}); got {self.polyorder}")

    @property
    def min_samples(self) -> int:
        self._validate_params()
        return max(self._windows())

    @property
    def halo(self) -> int:
        return max(self._windows()) // 2

    def _compute(self, x, t):
        dt = (t[-1] - t[0]) / (len(t) - 1)
        smooth, x_dot = np.empty_like(x), np.empty_like(x)
        windows = np.asarray(self._windows(x.shape[1]))
        for w in np.unique(windows):           # columns sharing a window: one call
            j = np.flatnonzero(windows == w)
            x_dot[:, j] = savgol(x[:, j], int(w), self.polyorder, deriv=1, delta=dt)
            smooth[:, j] = savgol(x[:, j], int(w), self.polyorder) if self.smooth else x[:, j]
        return smooth, x_dot


class _DerivativePackage(Differentiator):
    """Adapter for a method of the ``derivative`` package (``derivative.methods``)."""

    _kind: str

    def _method(self):
        from derivative import methods
        return methods[self._kind](**self._kwargs())

    def _kwargs(self) -> dict:
        return {k: v for k, v in self.get_params(deep=False).items() if k != "smooth"}

    def _compute(self, x, t):
        try:
            method = self._method()
            x_dot = method.d(x, t, axis=0)
            x_smooth = method.x(x, t, axis=0) if getattr(self, "smooth", False) else x
        except (ArithmeticError, ValueError, np.linalg.LinAlgError) as e:
            raise ConvergenceError(f"{self!r} failed on these data ({type(e).__name__}: {e}); "
                                   "try other parameters or another method") from e
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
    _parameter_constraints = {"s": [Interval(Real, 0, None)], "order": [Interval(Integral, 1, 5)],
                              "smooth": [bool]}

    def __init__(self, s: float = 0.0, order: int = 3, *, smooth: bool = True):
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
    _parameter_constraints = {"order": [Interval(Integral, 0, None)],
                              "alpha": [Interval(Real, 0, None, closed="neither")],
                              "max_iter": [Interval(Integral, 1, None)]}

    def __init__(self, order: int = 0, alpha: float = 1e-2, max_iter: int = 10000):
        self.order = order
        self.alpha = alpha
        self.max_iter = max_iter

    @property
    def min_samples(self) -> int:
        self._validate_params()
        return int(self.order) + 2   # the penalty takes (order + 1)-th differences


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
    _parameter_constraints = {"alpha": [Interval(Real, 0, None, closed="neither")],
                              "smooth": [bool]}

    def __init__(self, alpha: float = 1.0, *, smooth: bool = True):
        self.alpha = alpha
        self.smooth = smooth

    def _compute(self, x, t):
        if len(t) > self.max_samples:
            raise ParameterError(f"Kalman smoothing of {len(t)} samples would need a dense "
                                 f"{2 * len(t)}-square solve; split the trajectory into pieces "
                                 f"of at most {self.max_samples} samples or use SavitzkyGolay")
        x_smooth, x_dot = super()._compute(x, t)
        self._check_no_worse_than_a_line(x, t)
        return x_smooth, x_dot

    def _check_no_worse_than_a_line(self, x, t):
        """The smoother's limit (alpha -> inf) is the least-squares line; a fit worse than
        that line means the package's dense solve lost its accuracy (it then returns
        derivatives near 0 on some machines and raises on others)."""
        smooth = np.asarray(self._method().x(x, t, axis=0), float)
        basis = np.c_[np.ones_like(t), t - t.mean()]
        line = basis @ np.linalg.lstsq(basis, x, rcond=None)[0]
        worse = np.sum((x - smooth) ** 2, axis=0) > 1.001 * np.sum((x - line) ** 2, axis=0) \
            + 1e-12 * np.sum(x ** 2, axis=0)
        if np.any(worse) or not np.all(np.isfinite(smooth)):
            raise ConvergenceError(f"{self!r} failed on these data (its smoothed states fit "
                                   "worse than a straight line: the solve is ill-conditioned "
                                   "at this alpha); try a smaller alpha or another method")
