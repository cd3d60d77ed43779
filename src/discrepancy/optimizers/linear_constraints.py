"""Term masks and linear constraints on the coefficients, solved on the Gram statistics.

:class:`LinearConstraints` holds, in index form, which terms each equation may use and
linear equalities ``A_eq vec(Ξ) = b_eq`` and inequalities ``A_ub vec(Ξ) <= b_ub`` on the
stacked coefficients, in PySINDy's "target" order (``vec(Ξ)[i * p + j]`` is the coefficient
of term ``j`` in equation ``i``). The constrained least squares on given supports is

    minimise  Σ_i ξ_iᵀ (G + α I) ξ_i - 2 ξ_iᵀ b_i    subject to the constraints,

a small convex quadratic programme in the active coefficients only. scipy has no QP solver,
so it is solved by SLSQP (scipy) and then polished exactly: the inequalities active at
SLSQP's answer are made equalities and the KKT system is solved directly; the polished point
is kept when it is feasible with non-negative multipliers (it then is the optimum to
rounding), else SLSQP's point. Equalities alone need only the KKT solve.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..errors import ConvergenceError, ParameterError, ShapeError

FEASIBILITY = 1e-9


@dataclass(frozen=True)
class LinearConstraints:
    """Masks and linear constraints for ``n`` equations of ``p`` terms (index form).

    Attributes:
        mask: ``(n, p)`` booleans: terms each equation may use (``None``: all).
        eq_lhs, eq_rhs: ``(k, n p)``, ``(k,)``: ``eq_lhs @ vec(Ξ) = eq_rhs``.
        ub_lhs, ub_rhs: ``(l, n p)``, ``(l,)``: ``ub_lhs @ vec(Ξ) <= ub_rhs``.
        order: the layout of the given ``eq_lhs``/``ub_lhs`` columns: ``"target"`` (column
            ``i p + j``: term ``j`` of equation ``i``) or PySINDy's other
            ``constraint_order``, ``"feature"`` (column ``j n + i``); stored in target order
            (``order`` then reads ``"target"``).
    """

    n: int
    p: int
    mask: np.ndarray | None = None
    eq_lhs: np.ndarray | None = None
    eq_rhs: np.ndarray | None = None
    ub_lhs: np.ndarray | None = None
    ub_rhs: np.ndarray | None = None
    order: str = "target"

    def __post_init__(self):
        size = self.n * self.p
        if self.order not in ("target", "feature"):
            raise ParameterError(f"order must be 'target' or 'feature' (PySINDy's "
                                 f"constraint_order); got {self.order!r}")
        if self.mask is not None and np.shape(self.mask) != (self.n, self.p):
            raise ShapeError(f"mask must be ({self.n}, {self.p}); got {np.shape(self.mask)}")
        for lhs, rhs, what in ((self.eq_lhs, self.eq_rhs, "equality"),
                               (self.ub_lhs, self.ub_rhs, "inequality")):
            if (lhs is None) != (rhs is None):
                raise ShapeError(f"{what} constraints need both a left- and a right-hand side")
            if lhs is not None and (np.ndim(lhs) != 2 or np.shape(lhs)[1] != size or
                                    np.shape(rhs) != (np.shape(lhs)[0],)):
                raise ShapeError(f"{what} constraints must be (k, {size}) and (k,); got "
                                 f"{np.shape(lhs)} and {np.shape(rhs)}")
        if self.order == "feature":
            for name in ("eq_lhs", "ub_lhs"):
                if getattr(self, name) is not None:
                    object.__setattr__(self, name, reorder(np.asarray(getattr(self, name),
                                                                      float), self.n, self.p))
            object.__setattr__(self, "order", "target")

    def scaled(self, scale: np.ndarray) -> LinearConstraints:
        """The same constraints on coefficients of columns scaled by ``scale`` ``(p,)``
        (``ξ = scale * ξ_scaled``)."""
        if not self.has_linear or np.all(scale == 1):
            return self
        factor = np.tile(scale, self.n)
        return LinearConstraints(
            self.n, self.p, self.mask,
            None if self.eq_lhs is None else np.asarray(self.eq_lhs) * factor, self.eq_rhs,
            None if self.ub_lhs is None else np.asarray(self.ub_lhs) * factor, self.ub_rhs)

    @property
    def allowed(self) -> np.ndarray:
        """Boolean mask ``(n, p)`` of the coefficients that may be nonzero."""
        return np.ones((self.n, self.p), bool) if self.mask is None else np.asarray(self.mask)

    @property
    def has_linear(self) -> bool:
        """True when there are linear equality or inequality constraints besides the mask."""
        return self.eq_lhs is not None or self.ub_lhs is not None

    def involved(self) -> np.ndarray:
        """``(n, p)``: coefficients that appear in an equality constraint."""
        if self.eq_lhs is None:
            return np.zeros((self.n, self.p), bool)
        return np.any(np.asarray(self.eq_lhs) != 0, axis=0).reshape(self.n, self.p)


def reorder(lhs: np.ndarray, n: int, p: int) -> np.ndarray:
    """Constraint columns in PySINDy's "feature" order (``j n + i``) put in target order
    (``i p + j``) for ``n`` equations of ``p`` terms."""
    return lhs.reshape(len(lhs), p, n).transpose(0, 2, 1).reshape(len(lhs), n * p)


def constrained_solve(gram, rhs, support, constraints: LinearConstraints,
                      alpha: float = 0.0) -> np.ndarray:
    """Coefficients ``(n, p)`` minimising the (ridge) least squares on ``support`` ``(n, p)``
    subject to ``constraints``; raises ConvergenceError if they cannot be met there."""
    n, p = support.shape
    active = np.flatnonzero(support.ravel())
    coef = np.zeros(n * p)
    if active.size == 0:
        _check_zero_feasible(constraints)
        return coef.reshape(n, p)
    eq = restricted_rows(constraints.eq_lhs, constraints.eq_rhs, active)
    ub = restricted_rows(constraints.ub_lhs, constraints.ub_rhs, active)
    rows, cols = np.divmod(active, p)
    hessian = np.where(rows[:, None] == rows[None, :], gram[np.ix_(cols, cols)], 0.0) \
        + alpha * np.eye(active.size)
    linear = rhs[cols, rows]
    coef[active] = solve_qp(hessian, linear, eq, ub)
    # a coefficient the constraints pin to zero comes out as rounding (~1e-17): it is zero
    coef[np.abs(coef) < 1e-13 * max(1.0, float(np.max(np.abs(coef))))] = 0.0
    return coef.reshape(n, p)


def restricted_rows(lhs, rhs, active):
    """Constraint rows on the active coefficients; rows on inactive ones only (0 = rhs
    must then hold) are checked, not kept."""
    if lhs is None:
        return None
    lhs, rhs = np.asarray(lhs, float), np.asarray(rhs, float)
    keep = np.any(lhs[:, active] != 0, axis=1)
    return lhs[keep][:, active], rhs[keep], lhs[~keep], rhs[~keep]


def _check_zero_feasible(c: LinearConstraints) -> None:
    if c.eq_rhs is not None and np.any(np.abs(c.eq_rhs) > FEASIBILITY):
        raise ConvergenceError("the equality constraints cannot hold with every coefficient "
                               "zero; keep their terms in the library and the mask")
    if c.ub_rhs is not None and np.any(np.asarray(c.ub_rhs) < -FEASIBILITY):
        raise ConvergenceError("the inequality constraints cannot hold with every coefficient "
                               "zero")


def solve_qp(hessian, linear, eq, ub) -> np.ndarray:
    """argmin ½ xᵀHx - linearᵀx (H = 2 Gram, so x solves H x = 2 b) s.t. eq, ub."""
    h, g = 2 * hessian, 2 * linear
    for part in (eq, ub):  # rows of inactive coefficients only: must hold with zeros
        if part is not None and len(part[2]):
            bad = np.abs(part[3]) > FEASIBILITY if part is eq else part[3] < -FEASIBILITY
            if np.any(bad):
                raise ConvergenceError("a constraint on coefficients that are zero here "
                                       "cannot hold; keep its terms")
    a_eq = None if eq is None or not len(eq[0]) else eq[0]
    b_eq = None if a_eq is None else eq[1]
    a_ub = None if ub is None or not len(ub[0]) else ub[0]
    b_ub = None if a_ub is None else ub[1]
    if a_ub is None:
        return _kkt(h, g, a_eq, b_eq)[0]
    start = _slsqp(h, g, a_eq, b_eq, a_ub, b_ub)
    tight = np.abs(a_ub @ start - b_ub) <= 1e-7 * (1 + np.abs(b_ub))
    lhs = a_ub[tight] if a_eq is None else np.vstack([a_eq, a_ub[tight]])
    rhs = b_ub[tight] if a_eq is None else np.concatenate([b_eq, b_ub[tight]])
    x, multipliers = _kkt(h, g, lhs if len(lhs) else None, rhs if len(lhs) else None)
    n_eq = 0 if a_eq is None else len(a_eq)
    feasible = np.all(a_ub @ x <= b_ub + FEASIBILITY * (1 + np.abs(b_ub)))
    if feasible and np.all(multipliers[n_eq:] >= -1e-10):
        return x
    return start


def _kkt(h, g, a, b):
    """Minimiser of ½ xᵀhx - gᵀx with a x = b: ``(x, multipliers)``."""
    if a is None:
        return scipy.linalg.lstsq(h, g)[0], np.zeros(0)
    k = len(a)
    system = np.block([[h, a.T], [a, np.zeros((k, k))]])
    solution = scipy.linalg.lstsq(system, np.concatenate([g, b]))[0]
    x, lam = solution[:len(g)], solution[len(g):]  # h x + aᵀ λ = g: λ >= 0 for active a x <= b
    if np.max(np.abs(a @ x - b), initial=0) > 1e-7 * (1 + np.max(np.abs(b), initial=0)):
        raise ConvergenceError("the equality constraints are inconsistent (no coefficients "
                               "satisfy them all)")
    return x, lam


def _slsqp(h, g, a_eq, b_eq, a_ub, b_ub) -> np.ndarray:
    from scipy.optimize import minimize

    cons = [{"type": "ineq", "fun": lambda x: b_ub - a_ub @ x, "jac": lambda x: -a_ub}]
    if a_eq is not None:
        cons.append({"type": "eq", "fun": lambda x: a_eq @ x - b_eq, "jac": lambda x: a_eq})
    x0 = np.zeros(len(g))
    res = minimize(lambda x: 0.5 * x @ h @ x - g @ x, x0, jac=lambda x: h @ x - g,
                   constraints=cons, method="SLSQP", options={"ftol": 1e-15, "maxiter": 500})
    if not res.success and not np.all(a_ub @ res.x <= b_ub + 1e-6):
        raise ConvergenceError(f"the constrained least squares found no feasible point "
                               f"({res.message}); check that the constraints can hold together")
    return res.x
