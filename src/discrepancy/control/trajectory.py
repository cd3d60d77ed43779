"""Optimal open-loop plans with CasADi and IPOPT (direct multiple shooting).

The horizon ``[0, T]`` is split into ``n_intervals`` equal intervals; the input is
held constant on each (zero-order hold) and the state is carried across an
interval by ``substeps`` Runge–Kutta-4 steps, so the plan is an exact statement
about what the model does under that piecewise-constant input, up to RK4 error.
State bounds (a rail), input bounds and input-rate limits are hard constraints; when
IPOPT finds no plan, :mod:`.feasibility` says which limit or the horizon is to blame.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..constraints import Integral, Interval, Real, validate_params
from ..errors import ConvergenceError, InfeasibleError, ParameterError, ShapeError
from ..resources import check_memory, n_bytes
from .dynamics import as_casadi
from .limits import Limits
from .shooting import Problem, build, solver_options

COSTS = ("tracking", "effort")
PLAN_CONSTRAINTS = {"T": [Interval(Real, 0, closed="neither")],
                    "n_intervals": [Interval(Integral, 2)],
                    "substeps": [Interval(Integral, 1, 10_000)],
                    "max_iter": [Interval(Integral, 1)],
                    "tol": [Interval(Real, 0, closed="neither")]}
#: bytes of the NLP per interval and squared state-plus-input size (CasADi's expression graph
#: and IPOPT's derivative matrices; an estimate, for refusing absurd sizes before building)
NLP_BYTES_PER_ENTRY = 1000
#: the paper's swing-up state weights (φ1, φ2, s, dφ1, dφ2, ds), diagonal of ``Q``
PAPER_Q = (10.0, 10.0, 20.0, 1.0, 1.0, 0.1)
#: the paper's swing-up input weight ``R``
PAPER_R = 1.0


def check_plan(plan, name: str = "plan") -> None:
    """ParameterError unless ``plan`` is a :class:`Plan` (checked before any CasADi work)."""
    if not isinstance(plan, Plan):
        from ..errors import ParameterError, describe
        raise ParameterError(f"{name} must be a Plan (from plan_trajectory); got "
                             f"{describe(plan)}")


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
        cpu_time: CPU time of the whole call (building the problem and solving it, s).
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
    cpu_time: float = 0.0

    @property
    def dt(self) -> float:
        """The hold interval (s)."""
        return float(self.t[1] - self.t[0])


def _as_vector(name, value, size):
    v = np.asarray(value, dtype=float).ravel()
    if v.shape != (size,):
        raise ShapeError(f"{name} must have {size} entries; got shape {np.shape(value)}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(f"{name} must be finite; got {v}")
    return v


def default_guess(x0, xf, t, r):
    """Cosine blend from ``x0`` to ``xf`` with zero input: ``(x (N+1, n), u (N, r))``."""
    ramp = (1 - np.cos(np.pi * t / t[-1])) / 2
    x = x0 + np.outer(ramp, xf - x0)
    return x, np.zeros((len(t) - 1, r))


def resampled(plan: Plan, t: np.ndarray):
    """``(x (N+1, n), u (N, r))`` of ``plan`` on another grid ``t`` (states interpolated,
    held inputs looked up at the interval midpoints)."""
    x = np.column_stack([np.interp(t, plan.t, c) for c in plan.x.T])
    mid = t[:-1] + np.diff(t) / 2
    idx = np.clip(np.searchsorted(plan.t, mid) - 1, 0, len(plan.u) - 1)
    return x, plan.u[idx]


def state_names_of(model, n: int) -> tuple:
    """Names of the states for messages: the model's own, else ``x1 ... xn``."""
    for names in (getattr(model, "state_names_", None), getattr(model, "state_names", None)):
        if names is not None and len(names) == n:
            return tuple(str(s) for s in names)
    if isinstance(model, (tuple, list)) and len(model) == 3 and len(model[0]) == n:
        return tuple(str(s) for s in model[0])
    return tuple(f"x{i + 1}" for i in range(n))


def plan_trajectory(model, *, x0, xf, T=2.7, n_intervals=135, substeps=4, cost="tracking",
                    Q=None, R=1.0, x_ref=None, x_bounds=None, u_bounds=None, du_max=None,
                    limits: Limits | None = None, u_initial=None, initial_guess=None,
                    verbose=None, max_iter=1000, tol=1e-9, diagnose: bool = True) -> Plan:
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
        x_bounds: ``(n, 2)`` state bounds (``±inf`` for none); u_bounds: ``(r, 2)``;
            du_max: ``(r,)`` input rate limits (units per second), from ``u_initial``
            (default 0) on. Or all three as ``limits`` (a :class:`~.limits.Limits`).
        initial_guess: a :class:`Plan` (e.g. the plan of a nearby model) or ``None`` for a
            cosine blend from x0 to xf with zero input; if IPOPT fails from ``initial_guess``
            it tries the cosine blend before giving up.
        verbose: print IPOPT's iterations; ``None`` means only when stdout is a terminal.
        max_iter, tol: IPOPT options.
        diagnose: when IPOPT fails, solve relaxed problems to say which limit (or ``T``) is
            to blame (up to two more solves); ``False`` raises ConvergenceError at once.

    Raises:
        InfeasibleError: no plan meets the limits: names the state bound that is too tight
            and the range the task needs, or says that ``T`` is too short.
        ConvergenceError: IPOPT did not reach a solution for another reason (its status is
            in the message).
    """
    cpu0 = time.process_time()
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
    if limits is not None and (x_bounds is not None or u_bounds is not None
                               or du_max is not None):
        raise ParameterError("give limits, or x_bounds/u_bounds/du_max, not both")
    if limits is None:
        limits = Limits(x_bounds=x_bounds, u_bounds=u_bounds, du_max=du_max)
    x0, xf = _as_vector("x0", x0, n), _as_vector("xf", xf, n)
    x_ref = xf if x_ref is None else _as_vector("x_ref", x_ref, n)
    q = _as_vector("Q", np.ones(n) if Q is None else Q, n)
    xl, xu, ul, uu, du = limits.sized(n, r)
    u_init = np.zeros(r) if u_initial is None else _as_vector("u_initial", u_initial, r)
    t = np.linspace(0.0, T, n_intervals + 1)
    names = state_names_of(model, n)
    problem = Problem(f, x0, xf, t, substeps, xl, xu, ul, uu, du, u_init, names)
    for label, point in (("x0", x0), ("xf", xf)):
        outside = [i for i in range(n) if not xl[i] <= point[i] <= xu[i]]
        if outside:
            i = outside[0]
            raise InfeasibleError(f"{label} puts state {names[i]!r} at {point[i]:g}, outside "
                                  f"its bounds [{xl[i]:g}, {xu[i]:g}] (x_bounds)")

    def objective(X, U):
        dt = problem.dt
        if cost == "tracking":
            E = X[:, :-1] - ca.repmat(ca.DM(x_ref), 1, n_intervals)
            return dt * (ca.sum2(ca.sum1(ca.diag(ca.DM(q)) @ E ** 2)) + float(R) * ca.sumsqr(U))
        return dt * ca.sumsqr(U)

    opti, X, U, J, _ = build(problem, J_of=objective)
    guesses = [default_guess(x0, xf, t, r)]
    if initial_guess is not None:   # tried first; the cosine blend is the fallback
        guesses.insert(0, resampled(initial_guess, t))
    if verbose is None:
        verbose = sys.stdout.isatty()
    opti.solver("ipopt", *solver_options(verbose, max_iter, tol))
    start = time.perf_counter()
    for xg, ug in guesses:
        opti.set_initial(X, xg.T)
        opti.set_initial(U, np.clip(ug, ul, uu).T)
        try:
            sol = opti.solve()
            break
        except RuntimeError as e:
            failure = e
    else:
        stats = opti.stats()
        status = stats.get("return_status", "unknown")
        if not diagnose:
            raise ConvergenceError(f"IPOPT found no plan: status {status!r} after "
                                   f"{stats.get('iter_count', '?')} iterations (T={T} s)"
                                   ) from failure
        from .feasibility import explain

        explain(problem, objective, guesses, status)  # raises InfeasibleError if it can tell
        raise ConvergenceError(
            f"IPOPT found no plan: status {status!r} after {stats.get('iter_count', '?')} "
            f"iterations (T={T} s), but relaxed problems need no limit exceeded, so the limits "
            "are not to blame; try another initial_guess or more max_iter") from failure
    elapsed = time.perf_counter() - start
    stats = sol.stats()
    return Plan(t=t, x=np.array(sol.value(X)).T.reshape(-1, n),
                u=np.array(sol.value(U)).reshape(r, -1).T, cost=cost,
                objective=float(sol.value(J)), status=stats["return_status"],
                iterations=int(stats["iter_count"]), solve_time=elapsed, substeps=substeps,
                cpu_time=time.process_time() - cpu0)
