"""Sparse relaxed regularised regression (SR3) on Gram statistics.

The same iteration as PySINDy's ``SR3`` (Zheng et al. 2018; Champion et al. 2020): a relaxed
copy ``w`` of the coefficients is solved from ``(ΘᵀΘ + I/ν) w = Θᵀy + v/ν`` and the sparse
coefficients are its proximal step ``v = prox_{λν R}(w)``, starting from the least-squares
solution (or ``initial_guess``). Only ``ΘᵀΘ`` and ``Θᵀy`` are needed, so it streams and runs
on Dask like every other solver here. ``λ`` may differ per term (``reg_weight_lam`` an array,
the ``weighted_*`` regularizers: per-term thresholds).

Trimming (``trimming_fraction > 0``) weighs every sample by ``τ_i ∈ [0, 1]``, ``Σ τ = (1 - f)
m``, and moves ``τ`` down the gradient of each sample's residual, so outliers lose their
weight. That changes the weights of single samples at every iteration, which no sum over
samples can follow: trimming needs the rows and fits in memory only.
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg
from scipy.optimize import brentq

from ..constraints import Integral, Interval, Options, Predicate, Real
from ..errors import ConvergenceWarning, ParameterError, ShapeError
from .base import Optimizer, refit_on_support, register, solve_normal

PROX = {
    "l0": lambda w, lam: w * (np.abs(w) > np.sqrt(2 * lam)),
    "l1": lambda w, lam: np.sign(w) * np.maximum(np.abs(w) - lam, 0.0),
    "l2": lambda w, lam: w / (1 + 2 * lam),
}
REGULARIZERS = [*PROX, *(f"weighted_{r}" for r in PROX)]
#: ``reg_weight_lam``: one number, or an array of non-negative numbers (one per term)
LAMBDA = [Interval(Real, 0, None),
          Predicate(lambda v: _matrix(v) and bool(np.all(np.asarray(v) >= 0)),
                    "a 2-D array (n_targets, n_features) of finite numbers >= 0")]


def _matrix(v) -> bool:
    """A non-empty 2-D array (or nested list, as a model file stores it) of finite numbers."""
    if not isinstance(v, (np.ndarray, list, tuple)) or np.ndim(v) != 2 or np.size(v) == 0:
        return False
    a = np.asarray(v)
    return a.dtype.kind in "iuf" and bool(np.all(np.isfinite(a)))


def capped_simplex(v: np.ndarray, total: float) -> np.ndarray:
    """Euclidean projection of ``v`` onto ``{τ : 0 <= τ <= 1, Σ τ = total}``: ``clip(v - s,
    0, 1)`` with the shift ``s`` found by Brent's method (scipy)."""
    def excess(s):
        return np.sum(np.clip(v - s, 0.0, 1.0)) - total
    return np.clip(v - brentq(excess, np.min(v) - 1.0, np.max(v)), 0.0, 1.0)


@register("sr3")
class SR3(Optimizer):
    """Minimise ``½|y - Θw|² + λ R(v) + |w - v|²/(2ν)`` per target; ``coef_`` is ``v``.

    Args:
        reg_weight_lam: ``λ``: one number, or ``(n_targets, n_features)`` per-term weights
            (needed by the ``weighted_*`` regularizers). For ``"l0"`` a term survives when
            ``|w| > sqrt(2 λ ν)``: :meth:`calculate_l0_weight` turns a threshold into ``λ``.
        regularizer: ``"l0"``, ``"l1"``, ``"l2"`` (squared) or ``"weighted_l0"``,
            ``"weighted_l1"``, ``"weighted_l2"`` for ``R``.
        relax_coeff_nu: ``ν > 0``, how far ``w`` may stray from ``v``.
        tol: stop when ``|v_k - v_{k-1}|/ν`` (plus the trimming weights' step) ``< tol``.
        max_iter: iterations (a :class:`~discrepancy.errors.ConvergenceWarning` when spent).
        trimming_fraction: fraction of the samples to trim (0: none; needs the rows).
        trimming_step_size: gradient step of the trimming weights.
        initial_guess: ``(n_targets, n_features)`` start instead of least squares (of the
            normalised columns with ``normalize_columns``, as in PySINDy).
        normalize_columns: solve on unit-norm columns.
        unbias: least-squares refit on the final support.

    After fitting, ``coef_full_`` holds ``w``, ``n_iter_`` the iterations used and, with
    trimming, ``trimming_array_`` the samples' final weights (``history_trimming_`` all).
    """

    def __init__(self, reg_weight_lam=0.005, regularizer: str = "l0", *,
                 relax_coeff_nu: float = 1.0, tol: float = 1e-5, max_iter: int = 30,
                 trimming_fraction: float = 0.0, trimming_step_size: float = 1.0,
                 initial_guess=None, normalize_columns: bool = False, unbias: bool = False):
        self.reg_weight_lam = reg_weight_lam
        self.regularizer = regularizer
        self.relax_coeff_nu = relax_coeff_nu
        self.tol = tol
        self.max_iter = max_iter
        self.trimming_fraction = trimming_fraction
        self.trimming_step_size = trimming_step_size
        self.initial_guess = initial_guess
        self.normalize_columns = normalize_columns
        self.unbias = unbias

    _parameter_constraints = {"reg_weight_lam": LAMBDA,
                              "regularizer": [Options(REGULARIZERS)],
                              "relax_coeff_nu": [Interval(Real, 0, None, closed="neither")],
                              "tol": [Interval(Real, 0, None, closed="neither")],
                              "max_iter": [Interval(Integral, 1, None)],
                              "trimming_fraction": [Interval(Real, 0, 1, closed="left")],
                              "trimming_step_size": [Interval(Real, 0, None, closed="neither")],
                              "initial_guess": [None, Predicate(_matrix,
                                                                "a 2-D array of numbers")],
                              "normalize_columns": [bool], "unbias": [bool]}
    _rows_reason = "trimming weighs single samples"

    def _check_params(self):
        if self.regularizer.startswith("weighted") and np.ndim(self.reg_weight_lam) != 2:
            raise ParameterError(f"{type(self).__name__}: regularizer={self.regularizer!r} "
                                 "needs reg_weight_lam as an array (n_targets, n_features)")
        if self.trimming_fraction > 0 and self.unbias:
            raise ParameterError(f"{type(self).__name__}: unbias=True would undo the trimming; "
                                 "use trimming_fraction=0 or unbias=False")

    @staticmethod
    def calculate_l0_weight(threshold, relax_coeff_nu: float):
        """The ``"l0"`` weight ``λ = threshold² / (2ν)`` that keeps the terms with ``|w| >
        threshold`` (Champion et al. 2020, appendix S1)."""
        return np.square(threshold) / (2 * relax_coeff_nu)

    @property
    def needs_rows(self) -> bool:
        return self.trimming_fraction > 0

    @property
    def trimming_array(self) -> np.ndarray:
        """PySINDy's name of ``trimming_array_``."""
        self.check_is_fitted()
        return self.trimming_array_

    def _lam(self, stats, scale) -> np.ndarray | float:
        """``λ ν`` in the solver's ``(p, n)`` layout."""
        lam = self.reg_weight_lam
        if np.ndim(lam) == 2:
            if np.shape(lam) != (stats.n, stats.p):
                raise ShapeError(f"reg_weight_lam must be (n_targets, n_features) = "
                                 f"({stats.n}, {stats.p}); got {np.shape(lam)}")
            lam = np.asarray(lam, float).T
        return lam * float(self.relax_coeff_nu)

    def _start(self, stats, scale) -> np.ndarray:
        """The first sparse coefficients ``(p, n)``: least squares, or the initial guess
        (in the solver's column scaling)."""
        if self.initial_guess is None:
            return solve_normal(stats.gram, stats.rhs)
        if np.shape(self.initial_guess) != (stats.n, stats.p):
            raise ShapeError(f"initial_guess must be (n_targets, n_features) = ({stats.n}, "
                             f"{stats.p}); got {np.shape(self.initial_guess)}")
        return np.asarray(self.initial_guess, float).T  # as PySINDy: in the solver's columns

    def _solve(self, stats, scale):
        prox, lam = PROX[self.regularizer.replace("weighted_", "")], self._lam(stats, scale)
        full, sparse = relax(self, stats, self._start(stats, scale), prox, lam,
                             lambda gram: relaxed_solver(gram, float(self.relax_coeff_nu)))
        self.coef_full_ = full.T * scale[None, :]
        coef = sparse.T
        if self.unbias:
            coef = refit_on_support(stats.gram, stats.rhs, coef != 0)
        return coef



def relaxed_solver(gram, nu):
    """The relaxed update ``w = (G + I/ν)⁻¹ (Θᵀy + v/ν)`` for Gram matrix ``gram``."""
    factor = scipy.linalg.cho_factor(gram + np.eye(len(gram)) / nu)
    return lambda rhs, sparse: scipy.linalg.cho_solve(factor, rhs + sparse / nu)


def relax(solver, stats, sparse, prox, lam, make_update):
    """SR3's iterations for ``solver`` (its ``relax_coeff_nu``, ``tol``, ``max_iter`` and
    trimming options) from the sparse start ``(p, n)``: ``(w, v)``. ``make_update(G)`` gives
    the relaxed update ``(Θᵀy, v) -> w`` for Gram matrix ``G`` (with constraints, a KKT
    solve); with trimming it is remade as the samples' weights change."""
    nu, tol = float(solver.relax_coeff_nu), solver.tol
    trimming = getattr(solver, "trimming_fraction", 0) > 0
    if trimming:
        theta, y = stats.rows.weighted()
        m, step = theta.shape[0], solver.trimming_step_size
        tau = np.full(m, 1.0 - solver.trimming_fraction)
        history = [tau]
    else:
        update = make_update(stats.gram)
    full = sparse
    for n_iter in range(1, solver.max_iter + 1):
        solver.n_iter_ = n_iter
        if trimming:
            weighted = theta * tau[:, None]
            update = make_update(weighted.T @ theta)
            gradient = 0.5 * np.sum((y - theta @ full) ** 2, axis=1)
            full = update(weighted.T @ y, sparse)
        else:
            full = update(stats.rhs, sparse)
        previous, sparse = sparse, prox(full, lam)
        moved = np.sqrt(np.sum((sparse - previous) ** 2)) / nu
        if trimming:
            tau = capped_simplex(tau - step * gradient, (1.0 - solver.trimming_fraction) * m)
            history.append(tau)
            moved += np.sqrt(np.sum((history[-1] - history[-2]) ** 2)) / step
        if moved < tol:
            break
    else:
        warnings.warn(f"{type(solver).__name__} did not converge after {solver.max_iter} "
                      "iterations", ConvergenceWarning, stacklevel=6)
    if trimming:
        solver.trimming_array_, solver.history_trimming_ = tau, history
    return full, sparse
