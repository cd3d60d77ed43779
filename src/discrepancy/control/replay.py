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

from ..constraints import Integral, Interval, Real, validate_params
from ..data.validation import as_float_array, check_array, check_times
from ..errors import ConvergenceError, ParameterError, ShapeError, describe
from ..resources import check_memory, n_bytes

REPLAY_CONSTRAINTS = {"samples": [Interval(Integral, 1)],
                      "rtol": [Interval(Real, 0, closed="neither")],
                      "atol": [Interval(Real, 0, closed="neither")]}
#: Default success of reaching an upright target (angles 0): angles within 0.05 rad, rates 0.2.
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
        """The last state ``(n,)``."""
        return self.x[-1]


def swing_up_errors(x_final, *, angles, rates, angle_tol: float = ANGLE_TOL,
                    rate_tol: float = RATE_TOL) -> dict:
    """Final errors of a swing-up to the upright (all angles 0): ``|angle|`` (rad, wrapped
    to [-pi, pi)) of the state indices ``angles`` and ``|rate|`` of the indices ``rates``,
    keyed by index, and whether all meet the tolerances (``"success"``)."""
    x = check_array("x_final", np.reshape(as_float_array("x_final", x_final), (1, -1)))[0]
    validate_params("swing_up_errors", {"angle_tol": angle_tol, "rate_tol": rate_tol},
                    {"angle_tol": [Interval(Real, 0, None, closed="neither")],
                     "rate_tol": [Interval(Real, 0, None, closed="neither")]})
    for name, indices in (("angles", angles), ("rates", rates)):
        if not all(isinstance(i, (int, np.integer)) and -len(x) <= i < len(x) for i in indices):
            raise ShapeError(f"{name} must be indices of the {len(x)} states; got "
                             f"{list(indices)}")
    ang = np.abs((x[list(angles)] + np.pi) % (2 * np.pi) - np.pi)
    rate = np.abs(x[list(rates)])
    out = {f"angle_{i}": float(a) for i, a in zip(angles, ang, strict=True)}
    out |= {f"rate_{i}": float(r) for i, r in zip(rates, rate, strict=True)}
    out["success"] = bool(np.all(ang < angle_tol) and np.all(rate < rate_tol))
    return out


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
    """One hold interval by the package's integrator (DOP853, status and divergence
    checked there)."""
    from ..models.simulate.simulation import integrate

    grid = np.linspace(0.0, dt, samples + 1)

    def step(xk, uk):
        return integrate(f, xk, grid, lambda tau: uk, n_states=len(xk), n_inputs=len(uk),
                         method="DOP853", rtol=rtol, atol=atol)[1:]

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
    from .trajectory import check_plan
    check_plan(plan)
    validate_params("interval_defects", {"rtol": rtol, "atol": atol},
                    {"rtol": [Interval(Real, 0, 1, closed="right")],
                     "atol": [Interval(Real, 0, None, closed="neither")]})
    step = _stepper(model, plan.dt, 1, rtol, atol)
    return np.array([np.max(np.abs(step(plan.x[k], plan.u[k])[-1] - plan.x[k + 1]))
                     for k in range(len(plan.u))])


def _feedback(law, k: int, x: np.ndarray) -> np.ndarray:
    """``law(k, x)`` as a float vector, or ParameterError naming the law and the step."""
    try:
        value = law(k, x)
    except Exception as e:
        raise ParameterError(f"law raised {type(e).__name__} at step {k}: {e}") from e
    return check_array(f"law(k, x) at step {k}", np.reshape(as_float_array("law(k, x)", value),
                                                            (1, -1)))[0]


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
    validate_params("replay", {"samples": samples, "rtol": rtol, "atol": atol},
                    REPLAY_CONSTRAINTS)
    if np.ndim(t) != 1 or np.size(t) < 2:
        raise ShapeError(f"t must be increasing grid times (N+1,); got {describe(t)}")
    t = check_times("t", t, np.size(t))
    dts = np.diff(t)
    if np.ptp(dts) > 1e-9 * dts[0]:
        raise ParameterError("t must be uniformly spaced (a plan's grid)")
    x0 = check_array("x0", np.reshape(x0, (1, -1)))[0]
    n_int = len(t) - 1
    check_memory(f"the replay's dense output ({n_int} intervals x {samples + 1} samples x "
                 f"{len(x0)} states)", n_bytes((n_int, samples + 1, len(x0))),
                 "Ask for fewer samples per interval")
    if callable(law):
        feedback, table = law, None
    else:
        table = as_float_array("law", law)
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
        uk = table[k] if feedback is None else _feedback(feedback, k, xs[-1])
        seg = step(xs[-1], uk)
        if not np.all(np.isfinite(seg)):
            raise ConvergenceError(f"replay diverged on interval {k} (t = {t[k]:.3f} s)")
        dense.append(np.vstack([xs[-1], seg]))
        xs.append(seg[-1])
        us.append(uk)
    t_dense = t[:-1, None] + np.linspace(0.0, dts[0], samples + 1)[None, :]
    return Run(t=t, x=np.array(xs), u=np.array(us), t_dense=t_dense, x_dense=np.array(dense))
