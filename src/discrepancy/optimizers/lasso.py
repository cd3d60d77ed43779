"""The l1-penalised problem of the paper's eq. (3), solved on the Gram system."""
from __future__ import annotations

import warnings

import numpy as np

from ..constraints import Integral, Interval, Real
from ..errors import ConvergenceWarning
from .base import Optimizer, refit_on_support, register


@register("lasso")
class Lasso(Optimizer):
    """Minimise ``1/(2m) |y - Θξ|² + α |ξ|₁`` per target (scikit-learn's scaling).

    Solved by cyclic coordinate descent on ``ΘᵀΘ`` and ``Θᵀy`` (written here because
    scikit-learn's solver needs the m×p matrix, not its Gram statistics), with an
    optional unpenalised refit of the selected support.

    Args:
        alpha: l1 weight (units of y per unit of ξ, per sample).
        max_iter: coordinate sweeps.
        tol: stop when no coefficient moves more than ``tol`` times the largest.
        normalize_columns: solve on unit-norm columns (recommended for mixed libraries).
        unbias: least-squares refit on the selected support.
    """

    def __init__(self, alpha: float = 1e-3, *, max_iter: int = 10000, tol: float = 1e-10,
                 normalize_columns: bool = False, unbias: bool = False):
        self.alpha = alpha
        self.max_iter = max_iter
        self.tol = tol
        self.normalize_columns = normalize_columns
        self.unbias = unbias

    _parameter_constraints = {"alpha": [Interval(Real, 0, None)],
                              "max_iter": [Interval(Integral, 1, None)],
                              "tol": [Interval(Real, 0, None, closed="neither")],
                              "normalize_columns": [bool], "unbias": [bool]}

    def _solve(self, stats, scale):
        gram, rhs = stats.gram, stats.rhs
        penalty = self.alpha * (stats.count or 1)
        results = [self._descend(gram, rhs[:, i], penalty) for i in range(rhs.shape[1])]
        self.converged_ = np.array([ok for _, ok in results])
        if not self.converged_.all():  # as scikit-learn: the last iterate, with a warning
            warnings.warn(f"Lasso did not converge in {self.max_iter} sweeps for target(s) "
                          f"{np.flatnonzero(~self.converged_).tolist()}; raise max_iter, "
                          "loosen tol or use normalize_columns=True", ConvergenceWarning,
                          stacklevel=4)
        coef = np.array([c for c, _ in results])
        if self.unbias:
            coef = refit_on_support(gram, rhs, coef != 0)
        return coef

    def _descend(self, gram, rhs, penalty) -> tuple[np.ndarray, bool]:
        """Cyclic coordinate descent for one target: ``(coef (p,), converged)``."""
        diag = np.diag(gram)
        coef = np.zeros(len(rhs))
        for _ in range(self.max_iter):
            biggest_step = 0.0
            for j in np.flatnonzero(diag):
                rho = rhs[j] - gram[j] @ coef + diag[j] * coef[j]
                new = np.sign(rho) * max(abs(rho) - penalty, 0.0) / diag[j]
                biggest_step = max(biggest_step, abs(new - coef[j]))
                coef[j] = new
            if biggest_step <= self.tol * max(float(np.max(np.abs(coef))), 1e-300):
                return coef, True
        return coef, False
