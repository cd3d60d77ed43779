"""Finite differences of any accuracy and derivative order (PySINDy's ``FiniteDifference``).

The default (second order, first derivative) is ``numpy.gradient``: centred differences inside,
one-sided second-order differences at the ends, any sampling. Other orders use the stencil
every finite difference is: the weights ``w`` of ``x^(d)(t_i) ≈ Σ_k w_k x(t_i + h_k)`` solve
the Vandermonde system ``Σ_k w_k h_k^p = d! [p = d]``, ``p < len(stencil)`` (written here:
numpy and scipy have no arbitrary-order stencils on non-uniform grids). Stencils are centred
inside the record (``2 ((d + 1) // 2) - 1 + order`` samples, one more on the right for odd
orders); the ends either use the first (last) ``d + order`` samples, are NaN
(``drop_endpoints``: fits then drop those rows, as PySINDy's do), or wrap around
(``periodic``). The same choices as PySINDy's, so the answers agree to rounding.
"""
from __future__ import annotations

from math import factorial

import numpy as np

from ..constraints import Integral, Interval
from ..data.validation import is_uniform
from ..errors import ParameterError
from .base import Differentiator, register


def stencil_weights(offsets: np.ndarray, d: int) -> np.ndarray:
    """Weights ``(..., k)`` of the ``d``-th derivative from samples at ``offsets`` ``(..., k)``
    from the evaluation point (each row scaled by its largest offset for conditioning)."""
    scale = np.max(np.abs(offsets), axis=-1, keepdims=True)
    unit = offsets / scale
    k = offsets.shape[-1]
    vandermonde = unit[..., None, :] ** np.arange(k)[:, None]     # (..., power, sample)
    b = np.zeros(offsets.shape[:-1] + (k,))
    b[..., d] = factorial(d)
    return np.linalg.solve(vandermonde, b[..., None])[..., 0] / scale ** d


@register("finite_difference")
class FiniteDifference(Differentiator):
    """Finite differences (no smoothing); non-uniform ``t`` accepted.

    Args:
        order: accuracy order (error O(h^order)); 2 is centred differences.
        d: the derivative to take (1: velocity, 2: acceleration, ...).
        drop_endpoints: NaN where the centred stencil does not fit (fits drop those rows).
        periodic: the record is one period: stencils wrap around the ends (even ``order``;
            ``drop_endpoints`` takes precedence, as in PySINDy).

    As PySINDy's ``FiniteDifference(order, d, drop_endpoints=..., periodic=...)``; time is
    always axis 0 (PySINDy's ``axis`` and ``is_uniform`` are not needed).
    """

    _parameter_constraints = {"order": [Interval(Integral, 1, 20)],
                              "d": [Interval(Integral, 1, 10)],
                              "drop_endpoints": [bool], "periodic": [bool]}

    def __init__(self, order: int = 2, d: int = 1, *, drop_endpoints: bool = False,
                 periodic: bool = False):
        self.order = order
        self.d = d
        self.drop_endpoints = drop_endpoints
        self.periodic = periodic

    def _check_params(self):
        if self.d >= self._stencil:
            raise ParameterError(f"FiniteDifference: d={self.d} needs order >= "
                                 f"{self.d - self._stencil + self.order + 1} (a stencil of more "
                                 f"than d samples); got order={self.order}")
        if self.periodic and not self.drop_endpoints and self.order % 2:
            raise ParameterError("FiniteDifference: periodic=True needs an even order (centred "
                                 f"stencils); got order={self.order}")

    @property
    def _stencil(self) -> int:
        return 2 * ((self.d + 1) // 2) - 1 + self.order

    @property
    def _reach(self) -> tuple[int, int]:
        """Samples the centred stencil reaches to the left and to the right."""
        left = (self._stencil - 1) // 2
        return left, self._stencil - 1 - left

    @property
    def min_samples(self) -> int:
        self._validate_params()
        return max(self._stencil, self.d + self.order, 3)

    @property
    def halo(self) -> int | None:
        self._validate_params()
        return None if self.periodic and not self.drop_endpoints else max(self._reach)

    @property
    def dropped_rows(self) -> tuple[int, int]:
        return self._reach if self.drop_endpoints else (0, 0)

    def _compute(self, x, t):
        if (self.order, self.d, self.drop_endpoints, self.periodic) == (2, 1, False, False):
            return x, np.gradient(x, t, axis=0, edge_order=2)
        m = len(t)
        left, right = self._reach
        x_dot = np.full_like(x, np.nan)
        inside = np.arange(left, m - right)
        x_dot[inside] = self._apply(x, t, inside[:, None] + np.arange(-left, right + 1))
        ends = np.r_[np.arange(left), np.arange(m - right, m)].astype(int)
        if self.drop_endpoints:
            return x, x_dot
        if self.periodic:
            window = (ends[:, None] + np.arange(-left, right + 1)) % m
            x_dot[ends] = self._apply(x, t, window, at=ends, period=t[-1] - t[0] + t[1] - t[0])
        else:
            q = self.d + self.order
            window = np.where(ends[:, None] < left, np.arange(q), np.arange(m - q, m))
            x_dot[ends] = self._apply(x, t, window, at=ends)
        return x, x_dot

    def _apply(self, x, t, window, *, at=None, period=None) -> np.ndarray:
        """Derivatives at rows ``at`` (default: each window's centre) from the samples
        ``window`` ``(k, stencil)``: ``Σ_j w_j x[window_j]``."""
        if not len(window):
            return np.zeros((0, x.shape[1]))
        centred = at is None
        at = window[:, (self._stencil - 1) // 2] if centred else at
        offsets = t[window] - t[at][:, None]
        if period is not None:
            offsets = np.mod(offsets + period / 2, period) - period / 2
        if centred and is_uniform(t):
            weights = np.broadcast_to(stencil_weights(offsets[0], self.d), offsets.shape)
        else:
            weights = stencil_weights(offsets, self.d)
        return np.einsum("kj,kjn->kn", weights, x[window])
