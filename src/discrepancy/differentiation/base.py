"""Base class and registry of differentiation methods.

A method called as ``method(x, t)`` returns the derivative ``x_dot`` (PySINDy's contract:
the same shape as ``x``, ``t`` a step or the times) and keeps the smoothed samples in
``smoothed_x_``. Fits use :meth:`Differentiator.smooth_and_differentiate`, which returns
``(x_smooth, x_dot)``, both ``(m, n)``: ``x_smooth`` is what the library evaluates Θ on (the
paper smooths x with Savitzky–Golay and uses the smoothed x); methods that do not smooth
return ``x`` unchanged.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..base import Estimator
from ..data.validation import check_array, check_times, is_uniform
from ..errors import DataError, ShapeError
from ..registry import Registry


class Differentiator(Estimator, ABC):
    """Estimate time derivatives of sampled trajectories.

    Subclasses implement ``_compute(x, t)`` and set ``uniform_only``.
    ``halo`` is the number of neighbouring samples on each side a derivative
    depends on (used to stitch chunks exactly); ``None`` means global methods.
    """

    uniform_only: bool = False

    @property
    def min_samples(self) -> int:
        """Fewest samples a trajectory needs for this method."""
        return 3

    @property
    def halo(self) -> int | None:
        """Samples on each side a derivative depends on (``None``: the whole record, so the method
        cannot stream)."""
        return None

    @property
    def dropped_rows(self) -> tuple[int, int]:
        """Samples at the start and at the end whose derivative the method leaves undefined
        (NaN; fits drop those rows): ``(0, 0)`` unless it is asked to drop its endpoints."""
        return (0, 0)

    @property
    def edge(self) -> int:
        """Samples at each end whose estimate is an extrapolation (``halo``, or 0 for global
        methods that do not say otherwise)."""
        return self.halo or 0

    def __call__(self, x, t=1.0) -> np.ndarray:
        """The derivative of ``x`` ``(m, n)`` or ``(m,)`` at times ``t`` (a step, default 1
        as in PySINDy, or ``(m,)`` times), shaped like ``x``; the smoothed samples are kept
        in ``smoothed_x_`` (PySINDy's ``BaseDifferentiation`` contract)."""
        one_dimensional = np.ndim(x) == 1
        x_smooth, x_dot = self.smooth_and_differentiate(
            np.reshape(x, (-1, 1)) if one_dimensional else x, t)
        if one_dimensional:
            x_smooth, x_dot = x_smooth[:, 0], x_dot[:, 0]
        self.smoothed_x_ = x_smooth
        return x_dot

    def smooth_and_differentiate(self, x, t) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(x_smooth, x_dot)``, each ``(m, n)``, for ``x`` ``(m, n)`` at ``t`` (a step
        or ``(m,)`` times)."""
        self._validate_params()
        x = check_array("x", x)
        if np.ndim(t) not in (0, 1):
            raise ShapeError(f"t must be a step or an array of times (m,) for x of shape "
                             f"(m, n); got x {x.shape}, t {np.shape(t)}")
        t = check_times("t", t, x.shape[0])
        if x.shape[0] < self.min_samples:
            raise ShapeError(f"x has {x.shape[0]} samples, fewer than the {self.min_samples} that "
                             f"{self!r} needs (its window); give a longer trajectory or a "
                             "smaller window")
        if self.uniform_only and not is_uniform(t):
            raise DataError(f"{type(self).__name__} needs uniformly spaced t, but the steps of t "
                            f"range over [{np.diff(t).min():.6g}, {np.diff(t).max():.6g}]; "
                            "use FiniteDifference() or Spline(), which accept non-uniform t")
        x_smooth, x_dot = self._compute(x, t)
        return np.ascontiguousarray(x_smooth), np.ascontiguousarray(x_dot)

    @abstractmethod
    def _compute(self, x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Hook: smoothed x and its derivative, each (m, n)."""


METHODS = Registry("differentiation method", "differentiation_method", Differentiator)
register = METHODS.register


def available_methods() -> list[str]:
    """Names of the registered differentiation methods (the specs ``differentiation_method``
    accepts)."""
    return METHODS.names()


def get_differentiation_method(method=None, **kwargs) -> Differentiator:
    """A Differentiator from an instance, a registered name or spec text
    (``"savitzky_golay(window_length=31)"``, with ``kwargs``), a ``{"name", "params"}``
    mapping, or ``None``: ``"auto"``, smoothing chosen from the data
    (:class:`~discrepancy.differentiation.auto.AutoSmoothing`)."""
    return METHODS.create("auto" if method is None else method, **kwargs)
