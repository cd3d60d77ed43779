"""SR3 with linear equality and inequality constraints, on Gram statistics.

PySINDy's ``ConstrainedSR3`` in two regimes, each solved on ``ΘᵀΘ`` and ``Θᵀy``:

* equality constraints ``C vec(w) = d`` (any regularizer, trimming allowed): SR3's relaxed
  update becomes the equality-constrained least squares ``min ½ Σ_i w_iᵀ H w_i - g_iᵀ w_i``,
  ``H = ΘᵀΘ + I/ν``, solved by its KKT system (``w = H⁻¹ g + H⁻¹ Cᵀ μ``, ``μ`` from the
  ``k × k`` system ``C H⁻¹ Cᵀ μ = d - C H⁻¹ g``), then the proximal step as in SR3;
* inequality constraints ``C vec(ξ) <= d`` (with equalities after
  ``constraint_separation_index``; convex regularizers ``l1``, ``l2`` and their weighted
  forms): one convex problem ``min |y - Θξ|² + λ R(ξ)`` subject to the constraints, which
  PySINDy hands to CVXPY. Here it is a quadratic programme in the coefficients (``l1`` by
  splitting ``ξ = ξ⁺ - ξ⁻``) solved by scipy's SLSQP and polished on its active set by the
  KKT system (:mod:`discrepancy.optimizers.linear_constraints`): exact to rounding, where
  CVXPY stops at its tolerance ``tol``.

Constraints are in PySINDy's layout: ``constraint_order="target"`` (default; column
``i p + j`` is term ``j`` of equation ``i``) or ``"feature"`` (column ``j n + i``). They hold
for the coefficients in the data's units, also with ``normalize_columns`` (PySINDy's hold for
the normalised coefficients there).
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg

from ..constraints import InstanceOf, Integral, Interval, Options, Predicate
from ..errors import ParameterError, ShapeError
from .base import Optimizer, register
from .linear_constraints import LinearConstraints, reorder, restricted_rows, solve_qp
from .sr3 import LAMBDA, PROX, REGULARIZERS, SR3, relax, relaxed_solver

_MATRIX = Predicate(lambda v: np.ndim(v) == 2, "a 2-D array (constraints, n_targets n_features)")
_VECTOR = Predicate(lambda v: np.ndim(v) == 1, "a 1-D array (constraints,)")


@register("constrained_sr3")
class ConstrainedSR3(Optimizer):
    """SR3 subject to ``constraint_lhs @ vec(Ξ) = constraint_rhs`` (or ``<=``).

    Args:
        reg_weight_lam, regularizer, relax_coeff_nu, tol, max_iter: as :class:`SR3`.
        trimming_fraction, trimming_step_size, initial_guess, normalize_columns: as :class:`SR3`.
        constraint_lhs: ``(k, n_targets n_features)``.
        constraint_rhs: ``(k,)``.
        constraint_order: ``"target"`` or ``"feature"`` layout of ``constraint_lhs``.
        equality_constraints, inequality_constraints: which kind the rows are (neither:
            equalities, with a warning, as in PySINDy); with both, the first
            ``constraint_separation_index`` rows are inequalities and the rest equalities.
        constraints: a :class:`~discrepancy.optimizers.linear_constraints.LinearConstraints`
            (what ``DiscrepancyModel(constraints=...)`` sets from names), added to the rows.
        unbias: not with constraints (as in PySINDy).
    """

    def __init__(self, reg_weight_lam=0.005, regularizer: str = "l0", *,
                 relax_coeff_nu: float = 1.0, tol: float = 1e-5, max_iter: int = 30,
                 trimming_fraction: float = 0.0, trimming_step_size: float = 1.0,
                 constraint_lhs=None, constraint_rhs=None, constraint_order: str = "target",
                 equality_constraints: bool = False, inequality_constraints: bool = False,
                 constraint_separation_index: int | None = None, constraints=None,
                 initial_guess=None, normalize_columns: bool = False, unbias: bool = False):
        self.reg_weight_lam = reg_weight_lam
        self.regularizer = regularizer
        self.relax_coeff_nu = relax_coeff_nu
        self.tol = tol
        self.max_iter = max_iter
        self.trimming_fraction = trimming_fraction
        self.trimming_step_size = trimming_step_size
        self.constraint_lhs = constraint_lhs
        self.constraint_rhs = constraint_rhs
        self.constraint_order = constraint_order
        self.equality_constraints = equality_constraints
        self.inequality_constraints = inequality_constraints
        self.constraint_separation_index = constraint_separation_index
        self.constraints = constraints
        self.initial_guess = initial_guess
        self.normalize_columns = normalize_columns
        self.unbias = unbias

    _parameter_constraints = {
        **SR3._parameter_constraints, "reg_weight_lam": LAMBDA,
        "regularizer": [Options(REGULARIZERS)], "constraint_lhs": [None, _MATRIX],
        "constraint_rhs": [None, _VECTOR], "constraint_order": [Options(["target", "feature"])],
        "equality_constraints": [bool], "inequality_constraints": [bool],
        "constraint_separation_index": [None, Interval(Integral, 0, None)],
        "constraints": [None, InstanceOf(LinearConstraints, "LinearConstraints")]}
    _rows_reason = "trimming weighs single samples"

    @property
    def needs_rows(self) -> bool:
        return self.trimming_fraction > 0

    trimming_array = SR3.trimming_array
    calculate_l0_weight = staticmethod(SR3.calculate_l0_weight)

    def _check_params(self):
        SR3._check_params(self)
        if (self.constraint_lhs is None) != (self.constraint_rhs is None):
            raise ParameterError("ConstrainedSR3: give constraint_lhs and constraint_rhs "
                                 "together")
        rows = [np.shape(a)[0] for a in (self.constraint_lhs, self.constraint_rhs)
                if a is not None]
        if len(rows) == 2 and rows[0] != rows[1]:
            raise ShapeError(f"ConstrainedSR3: constraint_lhs has {rows[0]} rows, "
                             f"constraint_rhs {rows[1]} values")
        if self.unbias and self._constrained:
            raise ParameterError("ConstrainedSR3: unbias=True would break the constraints; "
                                 "set unbias=False")
        if self.inequality_constraints:
            if self.constraint_lhs is None:
                raise ParameterError("ConstrainedSR3: inequality_constraints=True needs "
                                     "constraint_lhs and constraint_rhs")
            if self.regularizer.endswith("l0"):
                raise ParameterError(f"ConstrainedSR3: inequality constraints need a convex "
                                     f"regularizer (l1, l2 or weighted); got {self.regularizer!r}")
            if self.equality_constraints and self.constraint_separation_index is None:
                raise ParameterError("ConstrainedSR3: with both equality and inequality "
                                     "constraints give constraint_separation_index (the "
                                     "first rows are the inequalities)")
        if self.trimming_fraction > 0 and self.inequality_constraints:
            raise ParameterError("ConstrainedSR3: trimming works with equality constraints "
                                 "only (the inequality problem is solved in one step)")

    @property
    def _constrained(self) -> bool:
        return self.constraint_lhs is not None or self.constraints is not None

    def _rows(self, n: int, p: int):
        """``(eq_lhs, eq_rhs, ub_lhs, ub_rhs)`` in target order (each may be None)."""
        eq, ub = [], []
        if self.constraint_lhs is not None:
            lhs = np.asarray(self.constraint_lhs, float)
            if lhs.shape[1] != n * p:
                raise ShapeError(f"constraint_lhs must have n_targets * n_features = {n * p} "
                                 f"columns; got {lhs.shape[1]}")
            lhs = reorder(lhs, n, p) if self.constraint_order == "feature" else lhs
            rhs = np.asarray(self.constraint_rhs, float)
            if not self.equality_constraints and not self.inequality_constraints:
                warnings.warn("ConstrainedSR3: constraint_lhs and constraint_rhs were given "
                              "without saying equality_constraints or inequality_constraints; "
                              "they are taken as equalities (as PySINDy does)", stacklevel=6)
            cut = 0 if not self.inequality_constraints else (
                len(lhs) if not self.equality_constraints else self.constraint_separation_index)
            ub.append((lhs[:cut], rhs[:cut]))
            eq.append((lhs[cut:], rhs[cut:]))
        if self.constraints is not None:
            c = self.constraints
            if (c.n, c.p) != (n, p):
                raise ShapeError(f"constraints are for {c.n} equations of {c.p} terms; the "
                                 f"data have {n} and {p}")
            masked = np.flatnonzero(~c.allowed.ravel())
            eq.append((np.eye(n * p)[masked], np.zeros(len(masked))))
            if c.eq_lhs is not None:
                eq.append((np.asarray(c.eq_lhs, float), np.asarray(c.eq_rhs, float)))
            if c.ub_lhs is not None:
                ub.append((np.asarray(c.ub_lhs, float), np.asarray(c.ub_rhs, float)))
        return _joined(eq, n * p) + _joined(ub, n * p)

    def _solve(self, stats, scale):
        n, p = stats.n, stats.p
        eq_lhs, eq_rhs, ub_lhs, ub_rhs = self._rows(n, p)
        factor = np.tile(scale, n)  # ξ = scale ξ_scaled: constraints in the data's units
        eq_lhs = None if eq_lhs is None else eq_lhs * factor
        ub_lhs = None if ub_lhs is None else ub_lhs * factor
        start = SR3._start(self, stats, scale)
        lam = SR3._lam(self, stats, scale) / float(self.relax_coeff_nu)
        if ub_lhs is not None:
            coef = _convex(stats, self.regularizer, lam, eq_lhs, eq_rhs, ub_lhs, ub_rhs)
            self.coef_full_, self.n_iter_ = start.T * scale[None, :], 1
            return coef
        prox = PROX[self.regularizer.replace("weighted_", "")]
        nu = float(self.relax_coeff_nu)
        make = (lambda gram: _equality_update(gram, nu, eq_lhs, eq_rhs)) if eq_lhs is not None \
            else (lambda gram: relaxed_solver(gram, nu))
        full, sparse = relax(self, stats, start, prox, lam * nu, make)
        self.coef_full_ = full.T * scale[None, :]
        return sparse.T


def _joined(parts, size):
    parts = [(a, b) for a, b in parts if len(a)]
    if not parts:
        return None, None
    return np.vstack([a for a, _ in parts]).reshape(-1, size), np.concatenate([b for _, b in parts])



def _equality_update(gram, nu, lhs, rhs):
    """The relaxed update under ``lhs vec(w) = rhs`` (target order): the KKT solution."""
    p = len(gram)
    n = lhs.shape[1] // p
    factor = scipy.linalg.cho_factor(gram + np.eye(p) / nu)
    blocks = [lhs[:, i * p:(i + 1) * p] for i in range(n)]                  # C_i (k, p)
    h_inv_ct = [scipy.linalg.cho_solve(factor, c.T) for c in blocks]        # H⁻¹ C_iᵀ (p, k)
    schur = sum(c @ h for c, h in zip(blocks, h_inv_ct, strict=True))     # C H⁻¹ Cᵀ (k, k)

    def update(b, sparse):
        free = scipy.linalg.cho_solve(factor, b + sparse / nu)              # (p, n)
        gap = rhs - sum(c @ free[:, i] for i, c in enumerate(blocks))
        mu = scipy.linalg.lstsq(schur, gap)[0]
        return free + np.column_stack([h @ mu for h in h_inv_ct])
    return update


def _convex(stats, regularizer, lam, eq_lhs, eq_rhs, ub_lhs, ub_rhs) -> np.ndarray:
    """``argmin |y - Θξ|² + λ R(ξ)`` subject to the constraints (R: l1 or l2, weighted or
    not), as a quadratic programme on the statistics; ``(n, p)``."""
    p, n = stats.rhs.shape
    size = n * p
    weights = np.broadcast_to(np.asarray(lam, float).T.ravel() if np.ndim(lam) == 2
                              else float(lam), (size,))  # target order
    gram = scipy.linalg.block_diag(*[stats.gram] * n)
    b = stats.rhs.T.ravel()
    if regularizer.endswith("l2"):
        hessian, linear, eq, ub = gram + np.diag(weights), b, (eq_lhs, eq_rhs), (ub_lhs, ub_rhs)
        split = None
    else:   # ξ = ξ⁺ - ξ⁻, both >= 0: λ|ξ| becomes linear
        hessian = np.block([[gram, -gram], [-gram, gram]])
        linear = np.concatenate([b - weights / 2, -b - weights / 2])
        eq = (None if eq_lhs is None else np.hstack([eq_lhs, -eq_lhs]), eq_rhs)
        ub_parts = [(-np.eye(2 * size), np.zeros(2 * size))]
        ub_parts.append((np.hstack([ub_lhs, -ub_lhs]), ub_rhs))
        ub = (np.vstack([a for a, _ in ub_parts]), np.concatenate([c for _, c in ub_parts]))
        split = size
    every = np.arange(hessian.shape[0])
    x = solve_qp(hessian, linear, restricted_rows(*eq, every) if eq[0] is not None else None,
            restricted_rows(*ub, every))
    coef = x if split is None else x[:split] - x[split:]
    coef[np.abs(coef) < 1e-12 * max(1.0, float(np.max(np.abs(coef))))] = 0.0
    return coef.reshape(n, p)
