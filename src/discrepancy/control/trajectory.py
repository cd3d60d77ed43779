"""Optimal open-loop plans with CasADi and IPOPT (direct multiple shooting).

The horizon ``[0, T]`` is split into ``n_intervals`` equal intervals; the input is
held constant on each (zero-order hold) and the state is carried across an
interval by ``substeps`` Runge–Kutta-4 steps, so the plan is an exact statement
about what the model does under that piecewise-constant input, up to RK4 error.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..constraints import Integral, Interval, Real, validate_params
from ..errors import ConvergenceError, ParameterError, ShapeError
from ..resources import check_memory, n_bytes
from .dynamics import as_casadi, rk4_step

COSTS = ("tracking", "effort")
PLAN_CONSTRAINTS = {"T": [Interval(Real, 0, closed="neither")],
                    "n_intervals": [Interval(Integral, 2)],
                    "substeps": [Interval(Integral, 1, 10_000)],
                    "max_iter": [Interval(Integral, 1)],
                    "tol": [Interval(Real, 0, closed="neither")]}
#: bytes of the NLP per interval and squared state-plus-input size (CasADi's expression graph
#: and IPOPT's derivative matrices; an estimate, for refusing absurd sizes before building)
NLP_BYTES_PER_ENTRY = 1000
PAPER_Q = (10.0, 10.0, 20.0, 1.0, 1.0, 0.1)
PAPER_R = 1.0


@dataclass(frozen=True)
class Plan:
    """An optimised plan.

    Attributes:
        t: grid times ``(N+1,)`` (s).
        x: planned states at the grid times ``(N+1, n)``.
        u: held inputs ``(N, r)``; ``u[k]`` acts on ``[t[k], t[k+1])``.
        cost: ``"tracking"`` or ``"effort"``; objective: its optimal value.
        status: IPOPT's return status; iterations; solve_time: IPOPT wall time (s).
        substeps: RK4 steps per interval used by the planner.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    cost: str
    objective: float
    status: str
    iterations: int
    solve_time: float
    substeps: int

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])


def _as_vector(name, value, size):
    v = np.asarray(value, dtype=float).ravel()
    if v.shape != (size,):
        raise ShapeError(f"{name} must have {size} entries; got shape {np.shape(value)}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(f"{name} must be finite; got {v}")
    return v


def _bounds(name, value, size):
    if value is None:
        return np.full(size, -np.inf), np.full(size, np.inf)
    b = np.asarray(value, dtype=float)
    if b.shape != (size, 2) or np.any(b[:, 0] > b[:, 1]):
        raise ShapeError(f"{name} must be ({size}, 2) rows of (lower, upper) with lower <= upper "
                         f"(use +-inf for none); got {b.tolist()}")
    return b[:, 0], b[:, 1]


def _finite(lower, upper) -> dict:
    return {i: (float(lo), float(hi)) for i, (lo, hi) in enumerate(zip(lower, upper, strict=True))
            if np.isfinite(lo) or np.isfinite(hi)}


def default_guess(x0, xf, t, r):
    """Cosine blend from ``x0`` to ``xf`` with zero input: ``(x (N+1, n), u (N, r))``."""
    ramp = (1 - np.cos(np.pi * t / t[-1])) / 2
    x = x0 + np.outer(ramp, xf - x0)
    return x, np.zeros((len(t) - 1, r))


def plan_trajectory(model, *, x0, xf, T=2.7, n_intervals=135, substeps=4, cost="tracking",
                    Q=None, R=1.0, x_ref=None, x_bounds=None, u_bounds=None,
                    initial_guess=None, verbose=None, max_iter=1000, tol=1e-9) -> Plan:
    """Plan inputs taking ``model`` from ``x0`` to ``xf`` in time ``T``.

    Args:
        model: CasADi dynamics f(x, u) -> xdot, or anything :func:`as_casadi` accepts
            (a hybrid model exports itself exactly from its sympy form).
        x0, xf: initial and required final state ``(n,)``.
        T: horizon (s); n_intervals: hold intervals; substeps: RK4 steps per interval.
        cost: ``"tracking"``: ``∫ (x - x_ref)ᵀ Q (x - x_ref) + R u² dt`` (the paper's, with
            ``x_ref = xf`` by default); ``"effort"``: ``∫ uᵀu dt``.
        Q: state weights ``(n,)`` (diagonal; default all 1); R: input weight (scalar).
            The paper's swing-up weights are ``PAPER_Q``, ``PAPER_R``.
        x_bounds: ``(n, 2)`` state bounds (``±inf`` for none); u_bounds: ``(r, 2)``.
        initial_guess: a :class:`Plan` (e.g. the plan of a nearby model) or ``None`` for a
            cosine blend from x0 to xf with zero input.
        verbose: print IPOPT's iterations; ``None`` means only when stdout is a terminal.
        max_iter, tol: IPOPT options.

    Raises:
        ConvergenceError: IPOPT did not reach a solution (its status is in the message),
            e.g. when ``T`` is too short for the bounds.
    """
    f = as_casadi(model)
    n, r = f.size1_in(0), f.size1_in(1)
    if cost not in COSTS:
        raise ParameterError(f"cost must be one of {COSTS}; got {cost!r}")
    validate_params("plan_trajectory", {"T": T, "n_intervals": n_intervals,
                                        "substeps": substeps, "max_iter": max_iter, "tol": tol},
                    PLAN_CONSTRAINTS)
    check_memory(f"a plan of {n_intervals} intervals", n_bytes((n_intervals, (n + r) ** 2,
                                                                  NLP_BYTES_PER_ENTRY)),
                 "Use fewer n_intervals")
    x0, xf = _as_vector("x0", x0, n), _as_vector("xf", xf, n)
    x_ref = xf if x_ref is None else _as_vector("x_ref", x_ref, n)
    q = _as_vector("Q", np.ones(n) if Q is None else Q, n)
    xl, xu = _bounds("x_bounds", x_bounds, n)
    ul, uu = _bounds("u_bounds", u_bounds, r)
    t = np.linspace(0.0, T, n_intervals + 1)
    dt = T / n_intervals
    step = rk4_step(f, dt, substeps).map(n_intervals, "serial")

    opti = ca.Opti()
    X = opti.variable(n, n_intervals + 1)
    U = opti.variable(r, n_intervals)
    opti.subject_to(X[:, 0] == x0)
    opti.subject_to(X[:, 1:] == step(X[:, :-1], U))
    opti.subject_to(X[:, -1] == xf)
    for i in range(n):
        if np.isfinite(xl[i]) or np.isfinite(xu[i]):
            opti.subject_to(opti.bounded(xl[i], X[i, 1:-1], xu[i]))
    for i in range(r):
        opti.subject_to(opti.bounded(ul[i], U[i, :], uu[i]))
    if cost == "tracking":
        E = X[:, :-1] - ca.repmat(ca.DM(x_ref), 1, n_intervals)
        J = dt * (ca.sum2(ca.sum1(ca.diag(ca.DM(q)) @ E ** 2)) + float(R) * ca.sumsqr(U))
    else:
        J = dt * ca.sumsqr(U)
    opti.minimize(J)

    if initial_guess is None:
        xg, ug = default_guess(x0, xf, t, r)
    else:
        xg = np.column_stack([np.interp(t, initial_guess.t, c) for c in initial_guess.x.T])
        tc = t[:-1] + dt / 2
        ug = np.column_stack([initial_guess.u[np.clip(np.searchsorted(initial_guess.t, tc) - 1,
                                                      0, len(initial_guess.u) - 1), i]
                              for i in range(r)])
    opti.set_initial(X, xg.T)
    opti.set_initial(U, ug.T)

    if verbose is None:
        verbose = sys.stdout.isatty()
    opti.solver("ipopt", {"print_time": False, "ipopt.sb": "yes"},
                {"print_level": 5 if verbose else 0, "max_iter": int(max_iter), "tol": tol,
                 "constr_viol_tol": 1e-10, "acceptable_iter": 0})
    start = time.perf_counter()
    try:
        sol = opti.solve()
    except RuntimeError as e:
        stats = opti.stats()
        raise ConvergenceError(
            f"IPOPT found no plan: status {stats.get('return_status', 'unknown')!r} after "
            f"{stats.get('iter_count', '?')} iterations (T={T} s, state bounds "
            f"{_finite(xl, xu)}, input bounds {_finite(ul, uu)}); a longer T or looser bounds "
            "may be needed") from e
    elapsed = time.perf_counter() - start
    stats = sol.stats()
    return Plan(t=t, x=np.array(sol.value(X)).T.reshape(-1, n),
                u=np.array(sol.value(U)).reshape(r, -1).T, cost=cost,
                objective=float(sol.value(J)), status=stats["return_status"],
                iterations=int(stats["iter_count"]), solve_time=elapsed, substeps=substeps)
