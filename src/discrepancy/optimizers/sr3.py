"""Sparse relaxed regularised regression (SR3) on Gram statistics.

The same iteration as PySINDy's ``SR3`` (Zheng et al. 2018; Champion et al. 2020) without
trimming: a relaxed copy ``w`` of the coefficients is solved from
``(ΘᵀΘ + I/ν) w = Θᵀy + v/ν`` and the sparse coefficients are its proximal step
``v = prox_{λν R}(w)``, starting from the least-squares solution. Only ``ΘᵀΘ`` and ``Θᵀy``
are needed, so it streams and runs on Dask like every other solver here.
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg

from ..constraints import Integral, Interval, Options, Real
from ..errors import ConvergenceWarning
from .base import Optimizer, register, solve_normal

PROX = {
    "l0": lambda w, lam: w * (np.abs(w) > np.sqrt(2 * lam)),
    "l1": lambda w, lam: np.sign(w) * np.maximum(np.abs(w) - lam, 0.0),
    "l2": lambda w, lam: w / (1 + 2 * lam),
}


@register("sr3")
class SR3(Optimizer):
    """Minimise ``½|y - Θw|² + λ R(v) + |w - v|²/(2ν)`` per target; ``coef_`` is ``v``.

    Args:
        reg_weight_lam: ``λ`` (for ``"l0"``, a term survives when ``|w| > sqrt(2 λ ν)``:
            ``λ = threshold² / (2ν)`` mimics a hard threshold).
        regularizer: ``"l0"``, ``"l1"`` or ``"l2"`` (squared) for ``R``.
        relax_coeff_nu: ``ν > 0``, how far ``w`` may stray from ``v``.
        tol: stop when ``|v_k - v_{k-1}|/ν < tol``.
        max_iter: iterations (a :class:`~discrepancy.errors.ConvergenceWarning` when spent).
        normalize_columns: solve on unit-norm columns.
        unbias: least-squares refit on the final support.

    After fitting, ``coef_full_`` holds ``w`` and ``n_iter_`` the iterations used.
    """

    def __init__(self, reg_weight_lam: float = 0.005, regularizer: str = "l0", *,
                 relax_coeff_nu: float = 1.0, tol: float = 1e-5, max_iter: int = 30,
                 normalize_columns: bool = False, unbias: bool = False):
        self.reg_weight_lam = reg_weight_lam
        self.regularizer = regularizer
        self.relax_coeff_nu = relax_coeff_nu
        self.tol = tol
        self.max_iter = max_iter
        self.normalize_columns = normalize_columns
        self.unbias = unbias

    _parameter_constraints = {"reg_weight_lam": [Interval(Real, 0, None)],
                              "regularizer": [Options(list(PROX))],
                              "relax_coeff_nu": [Interval(Real, 0, None, closed="neither")],
                              "tol": [Interval(Real, 0, None, closed="neither")],
                              "max_iter": [Interval(Integral, 1, None)],
                              "normalize_columns": [bool], "unbias": [bool]}

    def _solve(self, stats, scale):
        gram, rhs, nu = stats.gram, stats.rhs, float(self.relax_coeff_nu)
        prox = PROX[self.regularizer]
        sparse = solve_normal(gram, rhs)                        # (p, n), least squares
        factor = scipy.linalg.cho_factor(gram + np.eye(stats.p) / nu)
        self.n_iter_ = 0
        while self.n_iter_ < self.max_iter:
            self.n_iter_ += 1
            full = scipy.linalg.cho_solve(factor, rhs + sparse / nu)
            previous, sparse = sparse, prox(full, self.reg_weight_lam * nu)
            if np.sqrt(np.sum((sparse - previous) ** 2)) / nu < self.tol:
                break
        else:
            warnings.warn(f"SR3 did not converge after {self.max_iter} iterations",
                          ConvergenceWarning, stacklevel=4)
        self.coef_full_ = full.T * scale[None, :]
        coef = sparse.T
        if self.unbias:
            from .stlsq import STLSQ
            coef = STLSQ._refit(gram, rhs, coef != 0)
        return coef
