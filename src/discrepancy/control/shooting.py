"""The multiple-shooting problem of a plan: decision variables, dynamics, limits, objective.

:func:`build` turns a validated :class:`Problem` into a CasADi ``Opti``; the planner
(:mod:`~discrepancy.control.trajectory`) solves it, and
:mod:`~discrepancy.control.feasibility` solves relaxed versions of it.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .dynamics import rk4_step


@dataclass(frozen=True)
class Problem:
    """A validated planning problem (what :func:`build` turns into an ``Opti``)."""

    f: ca.Function
    x0: np.ndarray
    xf: np.ndarray
    t: np.ndarray
    substeps: int
    xl: np.ndarray
    xu: np.ndarray
    ul: np.ndarray
    uu: np.ndarray
    du_max: np.ndarray
    u_initial: np.ndarray
    state_names: tuple

    @property
    def dt(self) -> float:
        """The hold interval (s)."""
        return float(self.t[1] - self.t[0])

    @property
    def n_intervals(self) -> int:
        """Number of hold intervals."""
        return len(self.t) - 1


def build(p: Problem, *, J_of, elastic: str | None = None):
    """``(opti, X, U, J, slack)`` of problem ``p``; ``J_of(X, U)`` is the objective.

    ``elastic="states"``: each state bound may be exceeded by a slack ``>= 0`` (one per
    state), minimised first; ``"final"``: state bounds dropped and the final condition
    replaced by minimising the weighted distance to ``xf``. Used to diagnose failures.
    """
    n, N = len(p.x0), p.n_intervals
    r = len(p.ul)
    step = rk4_step(p.f, p.dt, p.substeps).map(N, "serial")
    opti = ca.Opti()
    X = opti.variable(n, N + 1)
    U = opti.variable(r, N)
    slack = None
    opti.subject_to(X[:, 0] == p.x0)
    opti.subject_to(X[:, 1:] == step(X[:, :-1], U))
    if elastic != "final":
        opti.subject_to(X[:, -1] == p.xf)
    bounded = [i for i in range(n) if np.isfinite(p.xl[i]) or np.isfinite(p.xu[i])]
    if elastic == "states" and bounded:
        slack = opti.variable(len(bounded))
        opti.subject_to(slack >= 0)
    for j, i in enumerate(bounded if elastic != "final" else []):
        s = 0 if slack is None else slack[j]
        if np.isfinite(p.xl[i]):
            opti.subject_to(X[i, 1:-1] >= p.xl[i] - s)
        if np.isfinite(p.xu[i]):
            opti.subject_to(X[i, 1:-1] <= p.xu[i] + s)
    for i in range(r):
        if np.isfinite(p.ul[i]) or np.isfinite(p.uu[i]):
            opti.subject_to(opti.bounded(p.ul[i], U[i, :], p.uu[i]))
        if np.isfinite(p.du_max[i]):
            d = p.du_max[i] * p.dt
            opti.subject_to(opti.bounded(-d, ca.horzcat(U[i, 0] - p.u_initial[i],
                                                        ca.diff(U[i, :], 1, 1)), d))
    J = J_of(X, U)
    if elastic == "states" and slack is not None:
        J = 1e3 * ca.sum1(slack) + 1e-6 * J
    elif elastic == "final":
        scale = np.maximum(np.abs(p.xf - p.x0), 1.0)
        J = ca.sumsqr((X[:, -1] - p.xf) / scale) + 1e-6 * J
    opti.minimize(J)
    return opti, X, U, J, slack


def solver_options(verbose, max_iter, tol):
    """IPOPT options for :meth:`casadi.Opti.solver` (silent unless ``verbose``)."""
    return ({"print_time": False, "ipopt.sb": "yes"},
            {"print_level": 5 if verbose else 0, "max_iter": int(max_iter), "tol": tol,
             "constr_viol_tol": 1e-10, "acceptable_iter": 0})
