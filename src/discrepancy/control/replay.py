"""Running an input law on a model with a tight ODE solve, one hold interval at a time.

The input is held constant on each interval of the plan's grid (zero-order hold),
exactly as the planner assumed, and the ODE is solved interval by interval, so
no solver step straddles an input jump. Feedback laws are sampled at the grid
times (a digital controller).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ..errors import ConvergenceError, ParameterError, ShapeError

#: Success of a swing-up (upright is 0): final |phi1|, |phi2| below 0.05 rad, rates below 0.2.
ANGLE_TOL = 0.05
RATE_TOL = 0.2


@dataclass(frozen=True)
class Run:
    """A simulated run.

    Attributes:
        t: grid times ``(N+1,)``; x: states there ``(N+1, n)``; u: applied inputs ``(N, r)``.
        t_dense: ``(N, S+1)`` sample times inside each interval, both ends included;
        x_dense: ``(N, S+1, n)`` states there (the input on interval k is ``u[k]``).
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    t_dense: np.ndarray
    x_dense: np.ndarray

    @property
    def final(self) -> np.ndarray:
        return self.x[-1]


def swing_up_errors(x_final) -> dict:
    """Final errors of a swing-up to upright: ``|phi1|, |phi2|`` (rad, wrapped to [-pi, pi))
    and ``|dphi1|, |dphi2|`` (rad/s), and whether they meet the success thresholds."""
    x = np.asarray(x_final, dtype=float)
    ang = np.abs((x[:2] + np.pi) % (2 * np.pi) - np.pi)
    rate = np.abs(x[3:5])
    return {"phi1": float(ang[0]), "phi2": float(ang[1]), "dphi1": float(rate[0]),
            "dphi2": float(rate[1]),
            "success": bool(np.all(ang < ANGLE_TOL) and np.all(rate < RATE_TOL))}


def _casadi_stepper(f: ca.Function, dt, samples, rtol, atol):
    n, r = f.size1_in(0), f.size1_in(1)
    x = ca.SX.sym("x", n)
    u = ca.SX.sym("u", r)
    grid = list(np.linspace(0.0, dt, samples + 1)[1:])
    F = ca.integrator("replay", "cvodes", {"x": x, "p": u, "ode": f(x, u)}, 0.0, grid,
                      {"reltol": rtol, "abstol": atol, "max_num_steps": 200000})

    def step(xk, uk):
        return np.array(F(x0=xk, p=uk)["xf"]).T

    return step


def _scipy_stepper(f: Callable, dt, samples, rtol, atol):
    grid = np.linspace(0.0, dt, samples + 1)[1:]

    def step(xk, uk):
        sol = solve_ivp(lambda _, y: f(y[None], uk[None])[0], (0.0, dt), xk, method="DOP853",
                        t_eval=grid, rtol=rtol, atol=atol)
        if not sol.success:
            raise ConvergenceError(f"solve_ivp failed during replay: {sol.message}")
        return sol.y.T

    return step


def _stepper(model, dt, samples, rtol, atol):
    if isinstance(model, ca.Function):
        return _casadi_stepper(model, dt, samples, rtol, atol)
    if callable(model):
        return _scipy_stepper(model, dt, samples, rtol, atol)
    raise ParameterError(f"model must be a casadi.Function or a callable f(x, u); got "
                         f"{type(model).__name__}")


def interval_defects(model, plan, *, rtol=1e-12, atol=1e-14) -> np.ndarray:
    """Per-interval integration error of a plan ``(N,)``: max-abs difference between the
    planned ``x[k+1]`` and a tight ODE solve over one interval from the planned ``x[k]``
    with ``u[k]`` held. Unlike a whole replay, these are not amplified by instability."""
    step = _stepper(model, plan.dt, 1, rtol, atol)
    return np.array([np.max(np.abs(step(plan.x[k], plan.u[k])[-1] - plan.x[k + 1]))
                     for k in range(len(plan.u))])


def replay(model, x0, t, law, *, samples=1, rtol=1e-12, atol=1e-14) -> Run:
    """Simulate ``model`` from ``x0`` on grid ``t`` under a held input law.

    Args:
        model: CasADi Function f(x, u) -> xdot (solved with CVODES) or a vectorised numpy
            callable ``f(x (m, n), u (m, r)) -> (m, n)`` such as ``System.rhs`` (solved
            with scipy's DOP853).
        x0: initial state ``(n,)``; t: grid times ``(N+1,)``, e.g. ``plan.t``.
        law: held inputs ``(N, r)`` (e.g. ``plan.u``) or a feedback ``law(k, x_k) -> (r,)``
            evaluated at each grid time.
        samples: output samples per interval (for plots and identification).
        rtol, atol: ODE tolerances.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or len(t) < 2 or np.any(np.diff(t) <= 0):
        raise ShapeError(f"t must be increasing grid times (N+1,); got shape {t.shape}")
    dts = np.diff(t)
    if np.ptp(dts) > 1e-9 * dts[0]:
        raise ParameterError("t must be uniformly spaced (a plan's grid)")
    x0 = np.asarray(x0, dtype=float).ravel()
    n_int = len(t) - 1
    if callable(law):
        feedback, table = law, None
    else:
        table = np.asarray(law, dtype=float)
        if table.ndim == 1:
            table = table[:, None]
        if table.shape[0] != n_int:
            raise ShapeError(f"law must have one input row per interval ({n_int}); got "
                             f"shape {table.shape}")
        feedback = None
    step = _stepper(model, dts[0], samples, rtol, atol)
    xs = [x0]
    us, dense = [], []
    for k in range(n_int):
        uk = np.asarray(table[k] if feedback is None else feedback(k, xs[-1]), dtype=float)
        uk = uk.ravel()
        seg = step(xs[-1], uk)
        if not np.all(np.isfinite(seg)):
            raise ConvergenceError(f"replay diverged on interval {k} (t = {t[k]:.3f} s)")
        dense.append(np.vstack([xs[-1], seg]))
        xs.append(seg[-1])
        us.append(uk)
    t_dense = t[:-1, None] + np.linspace(0.0, dts[0], samples + 1)[None, :]
    return Run(t=t, x=np.array(xs), u=np.array(us), t_dense=t_dense, x_dense=np.array(dense))
