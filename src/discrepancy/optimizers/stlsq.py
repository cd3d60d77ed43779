"""Sequentially thresholded least squares (STLSQ) on Gram statistics.

Same algorithm and answer as PySINDy's ``STLSQ`` (ridge-regularised regressions
on the active set, hard threshold ``|ξ| >= threshold`` keeps a term, stop when
the support no longer changes, then an unregularised refit on the support),
but every regression is a p×p solve, so the cost does not grow with the data.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..constraints import InstanceOf, Integral, Interval, Options, Real
from ..errors import ConvergenceWarning, ParameterError, ShapeError
from .base import Optimizer, refit_on_support, register
from .linear_constraints import LinearConstraints, constrained_solve

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
        constraints: a :class:`~discrepancy.optimizers.linear_constraints.LinearConstraints`
            (terms each equation may use; linear equalities and inequalities on the
            coefficients, PySINDy's "target" order), honoured by every solve. Coefficients
            in an equality constraint are never thresholded away. ``DiscrepancyModel``
            builds them from names (:class:`discrepancy.Constraints`).
    """

    def __init__(self, threshold: float = 0.1, alpha: float = 0.05, *, max_iter: int = 20,
                 normalize_columns: bool = False, unbias: bool = True, constraints=None):
        self.threshold = threshold
        self.alpha = alpha
        self.max_iter = max_iter
        self.normalize_columns = normalize_columns
        self.unbias = unbias
        self.constraints = constraints

    _parameter_constraints = {"threshold": [NON_NEGATIVE, Options(["auto"])],
                              "alpha": [NON_NEGATIVE], "max_iter": [Interval(Integral, 1, None)],
                              "normalize_columns": [bool], "unbias": [bool],
                              "constraints": [None, InstanceOf(LinearConstraints,
                                                               "LinearConstraints")]}

    def _solve(self, stats, scale):
        constraints = self._constraints(stats, scale)
        if self.threshold != "auto":
            self.thresholds_ = np.full(stats.n, float(self.threshold))
            return self._solve_fixed(stats.gram, stats.rhs, constraints)
        if stats.yy is None or not stats.count:
            raise ParameterError("threshold='auto' needs the targets' sums of squares: call "
                                 "fit(theta, y), or fit_gram(gram, rhs, n_samples=m, yy=Σy²)")
        from .selection import select_thresholds
        coef, self.thresholds_, self.selection_ = select_thresholds(self, stats, constraints)
        if constraints.has_linear:  # the chosen supports, refitted under the constraints
            keep = (coef != 0) | (constraints.involved() & constraints.allowed)
            coef = constrained_solve(stats.gram, stats.rhs, keep, constraints)
        return coef

    def _constraints(self, stats, scale) -> LinearConstraints:
        """The constraints for these statistics, in the solver's (column-scaled) units."""
        c = self.constraints or LinearConstraints(stats.n, stats.p)
        if (c.n, c.p) != (stats.n, stats.p):
            raise ShapeError(f"constraints are for {c.n} equations of {c.p} terms; the data "
                             f"have {stats.n} and {stats.p}")
        return c.scaled(scale)

    def _solve_fixed(self, gram, rhs, constraints=None):
        p, n = rhs.shape
        constraints = constraints or LinearConstraints(n, p)
        keep = constraints.involved() & constraints.allowed
        ind = constraints.allowed.copy()
        coef = np.zeros((n, p))
        for _ in range(self.max_iter):
            if not ind.any():
                warnings.warn(f"threshold {self.threshold} eliminated all coefficients",
                              stacklevel=3)
                break
            previous = ind.copy()
            if constraints.has_linear:
                coef = constrained_solve(gram, rhs, ind, constraints, self.alpha)
            else:
                coef = refit_on_support(gram, rhs, ind, self.alpha)
            ind = ((np.abs(coef) >= self.threshold) | keep) & constraints.allowed
            coef[~ind] = 0.0
            if np.array_equal(ind, previous):
                break
        else:
            warnings.warn(f"STLSQ did not converge after {self.max_iter} iterations",
                          ConvergenceWarning, stacklevel=3)
        if self.unbias:
            support = ind | keep   # the thresholded support (no absolute cut-off: units vary)
            coef = constrained_solve(gram, rhs, support, constraints) if constraints.has_linear \
                else refit_on_support(gram, rhs, support)
        return coef
