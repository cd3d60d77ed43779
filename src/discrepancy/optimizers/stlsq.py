"""Sequentially thresholded least squares (STLSQ) on Gram statistics.

Same algorithm and answer as PySINDy's ``STLSQ`` (ridge-regularised regressions
on the active set, hard threshold ``|ξ| >= threshold`` keeps a term, stop when
the support no longer changes, then an unregularised refit on the support),
but every regression is a p×p solve, so the cost does not grow with the data.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..constraints import Integral, Interval, Options, Real
from ..errors import ParameterError
from .base import Optimizer, register, solve_normal

NON_NEGATIVE = Interval(Real, 0, None)


@register("stlsq")
class STLSQ(Optimizer):
    """Sequentially thresholded ridge regression.

    Args:
        threshold: coefficients with ``|ξ| < threshold`` are set to zero (units of y / Θ);
            ``"auto"`` picks it per target by cross-validation over contiguous blocks of
            samples along the whole threshold path (see
            :mod:`discrepancy.optimizers.selection`). The chosen values are in
            ``thresholds_``, the scored path in ``selection_``.
        alpha: ridge weight ``α`` in ``|y - Θξ|² + α|ξ|²`` during thresholding.
        max_iter: maximum thresholding iterations.
        normalize_columns: threshold on coefficients of unit-norm columns.
        unbias: refit the final support without the ridge term (PySINDy's default).
    """

    def __init__(self, threshold: float = 0.1, alpha: float = 0.05, *, max_iter: int = 20,
                 normalize_columns: bool = False, unbias: bool = True):
        self.threshold = threshold
        self.alpha = alpha
        self.max_iter = max_iter
        self.normalize_columns = normalize_columns
        self.unbias = unbias

    _parameter_constraints = {"threshold": [NON_NEGATIVE, Options(["auto"])],
                              "alpha": [NON_NEGATIVE], "max_iter": [Interval(Integral, 1, None)],
                              "normalize_columns": [bool], "unbias": [bool]}

    def _solve(self, stats):
        if self.threshold != "auto":
            self.thresholds_ = np.full(stats.n, float(self.threshold))
            return self._solve_fixed(stats.gram, stats.rhs)
        if stats.yy is None or not stats.count:
            raise ParameterError("threshold='auto' needs the targets' sums of squares: call "
                                 "fit(theta, y), or fit_gram(gram, rhs, n_samples=m, yy=Σy²)")
        from .selection import select_thresholds
        coef, self.thresholds_, self.selection_ = select_thresholds(self, stats)
        return coef

    def _solve_fixed(self, gram, rhs):
        p, n = rhs.shape
        ind = np.ones((n, p), dtype=bool)
        coef = np.zeros((n, p))
        for _ in range(self.max_iter):
            if not ind.any():
                warnings.warn(f"threshold {self.threshold} eliminated all coefficients",
                              stacklevel=3)
                break
            previous = ind.copy()
            coef = np.zeros((n, p))
            for i in range(n):
                s = ind[i]
                if not s.any():
                    continue
                coef[i, s] = solve_normal(gram[np.ix_(s, s)], rhs[s, i], self.alpha)
                ind[i] = np.abs(coef[i]) >= self.threshold
                coef[i, ~ind[i]] = 0.0
            if np.array_equal(ind, previous):
                break
        else:
            warnings.warn(f"STLSQ did not converge after {self.max_iter} iterations",
                          stacklevel=3)
        if self.unbias:
            coef = self._refit(gram, rhs, np.abs(coef) > 1e-14)
        return coef

    @staticmethod
    def _refit(gram, rhs, support):
        coef = np.zeros(support.shape)
        for i, s in enumerate(support):
            if s.any():
                coef[i, s] = solve_normal(gram[np.ix_(s, s)], rhs[s, i])
        return coef
