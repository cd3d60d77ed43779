"""Nonlinear model predictive control on a (hybrid) model: CasADi Opti, IPOPT, warm starts.

At every sample the controller solves, by direct multiple shooting over ``horizon`` hold
intervals of ``dt`` (``substeps`` RK4 steps each, as the planner)::

    min  Σ_j (x_j - r_j)ᵀ Q (x_j - r_j) + (u_j - v_j)ᵀ R (u_j - v_j)
         + (x_N - r_N)ᵀ P (x_N - r_N) + ρ Σ (σ + σ²)
    s.t. x_0 = measured state, x_{j+1} = step(x_j, u_j),
         input bounds, |u_j - u_{j-1}| <= du_max dt (u_{-1}: the input applied last),
         state bounds widened by slacks σ >= 0 (soft, so a noisy measurement past a bound
         never makes the problem infeasible),

with ``r``, ``v`` a window of the reference (a plan, then its final state held) and ``P``
the tracking LQR's cost-to-go at the window's end. Each solve starts from the previous
solution shifted by one sample. Two solvers:

* ``solver="rti"`` (real time): one Gauss-Newton SQP step per sample on the condensed QP
  (:mod:`.rti`), solved by a dense QP solver (``qp_solver``, DAQP by default), optionally as
  compiled C (``compile=True``). Its cost per sample is fixed and well under a millisecond
  for a 6-state model over 20 intervals; the QP's solution is the step, so limits hold
  exactly for the linearised prediction.
* ``solver="ipopt"`` (the reference): the NLP built once with
  :meth:`casadi.Opti.to_function`, IPOPT warm-started; ``max_iter`` caps its iterations
  (a small fixed number is a real-time mode, though IPOPT's cost per iteration is several
  times the whole real-time iteration).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..constraints import Integral, Interval, Options, Real, validate_params
from ..data.validation import as_float_array, check_finite, check_vector
from ..errors import ParameterError, ShapeError
from .dynamics import as_casadi, rk4_step
from .limits import Limits
from .rti import RealTimeIteration
from .tracking import tvlqr, weight_matrix
from .trajectory import Plan, check_plan

#: solvers and their default iterations per sample
SOLVERS = {"ipopt": 100, "rti": 1}
#: MPC's declared parameter constraints, checked before any CasADi work (numpy integers are
#: integers; the sizes are bounded so that a typo cannot build a problem without end)
PARAMETERS = {
    "horizon": [Interval(Integral, 2, 10_000)],
    "substeps": [Interval(Integral, 1, 1000)],
    "soft_penalty": [Interval(Real, 0, None, closed="neither")],
    "solver": [Options(list(SOLVERS))],
    "max_iter": [None, Interval(Integral, 1, 100_000)],
    "tol": [Interval(Real, 0, None, closed="neither")],
    "compile": [bool],
}


class MPC:
    """Nonlinear MPC controller on ``model`` (see the module docstring for the problem).

    Args:
        model: the prediction model (anything :func:`~.dynamics.as_casadi` accepts: a
            fitted hybrid model, sympy equations, a CasADi Function).
        dt: control period = hold interval (s); horizon: prediction intervals ``N`` (>= 2).
        Q, R: stage weights (diagonal entries or matrices); default identity and 1.
        limits: a :class:`~.limits.Limits`: input bounds and rates hard, state bounds soft.
        substeps: RK4 steps per interval in the prediction.
        soft_penalty: ``ρ``, weight of the state-bound slacks (per unit of excess).
        solver: ``"ipopt"`` (reference NLP solver) or ``"rti"`` (real-time iteration).
        max_iter: iterations per sample: IPOPT's cap (default 100) or the number of SQP
            steps of the real-time iteration (default 1).
        tol: IPOPT's tolerance per sample.
        qp_solver: the real-time iteration's QP solver (a CasADi conic: ``"daqp"``,
            ``"qpoases"``, ``"osqp"``, ``"qrqp"``, ...).
        compile: the real-time iteration's functions as compiled C, cached on disk
            (:func:`~discrepancy.hybrid.codegen.compiled`; needs a C compiler, else warns and
            runs uncompiled).
    """

    def __init__(self, model, *, dt: float, horizon: int = 25, Q=None, R=1.0,
                 limits: Limits | None = None, substeps: int = 2, soft_penalty: float = 1e4,
                 solver: str = "ipopt", max_iter: int | None = None, tol: float = 1e-6,
                 qp_solver: str = "daqp", compile: bool = False):
        if not Interval(Real, 0, None, closed="neither").is_satisfied_by(dt):
            raise ParameterError(f"dt must be a positive time step (s); got {dt!r}")
        validate_params("MPC", dict(horizon=horizon, substeps=substeps,
                                    soft_penalty=soft_penalty, solver=solver,
                                    max_iter=max_iter, tol=tol, compile=compile),
                        PARAMETERS)
        f = as_casadi(model)
        n, r = f.size1_in(0), f.size1_in(1)
        horizon, substeps = int(horizon), int(substeps)
        max_iter = SOLVERS[solver] if max_iter is None else int(max_iter)
        self.n, self.r, self.dt, self.horizon = n, r, float(dt), horizon
        self.Q = weight_matrix("Q", np.ones(n) if Q is None else Q, n)
        self.R = weight_matrix("R", R, r)
        self.limits = Limits() if limits is None else limits
        self.substeps, self.max_iter, self.solver = substeps, max_iter, solver
        self.soft_penalty = float(soft_penalty)
        self._model = model
        if solver == "rti":
            self._rti = RealTimeIteration(
                f, dt=self.dt, substeps=substeps, horizon=horizon, Q=self.Q, R=self.R,
                bounds=self.limits.sized(n, r), soft_penalty=soft_penalty,
                qp_solver=qp_solver, compile=compile)
        else:
            self._function = self._build(f, soft_penalty, tol)

    def _build(self, f, soft_penalty, tol):
        n, r, N = self.n, self.r, self.horizon
        xl, xu, ul, uu, du = self.limits.sized(n, r)
        bounded = [i for i in range(n) if np.isfinite(xl[i]) or np.isfinite(xu[i])]
        opti = ca.Opti()
        X, U = opti.variable(n, N + 1), opti.variable(r, N)
        S = opti.variable(max(len(bounded), 1), N)
        x0, u_prev = opti.parameter(n), opti.parameter(r)
        Xr, Ur, P = opti.parameter(n, N + 1), opti.parameter(r, N), opti.parameter(n, n)
        step = rk4_step(f, self.dt, self.substeps).map(N, "serial")
        opti.subject_to(X[:, 0] == x0)
        opti.subject_to(X[:, 1:] == step(X[:, :-1], U))
        for i in range(r):
            if np.isfinite(ul[i]) or np.isfinite(uu[i]):
                opti.subject_to(opti.bounded(ul[i], U[i, :], uu[i]))
            if np.isfinite(du[i]):
                d = du[i] * self.dt
                opti.subject_to(opti.bounded(-d, ca.horzcat(U[i, 0] - u_prev[i],
                                                            ca.diff(U[i, :], 1, 1)), d))
        opti.subject_to(ca.vec(S) >= 0)
        for j, i in enumerate(bounded):
            if np.isfinite(xl[i]):
                opti.subject_to(X[i, 1:] + S[j, :] >= xl[i])
            if np.isfinite(xu[i]):
                opti.subject_to(X[i, 1:] - S[j, :] <= xu[i])
        E, V = X - Xr, U - Ur
        J = ca.sum2(ca.sum1(E[:, :-1] * (ca.DM(self.Q) @ E[:, :-1]))) \
            + ca.sum2(ca.sum1(V * (ca.DM(self.R) @ V))) + ca.bilin(P, E[:, -1], E[:, -1]) \
            + soft_penalty * (ca.sum1(ca.sum2(S)) + ca.sumsqr(S))
        opti.minimize(J)
        opti.solver("ipopt", {"print_time": False, "ipopt.sb": "yes", "expand": False,
                              "error_on_fail": False},
                    {"print_level": 0, "max_iter": self.max_iter, "tol": tol,
                     "acceptable_tol": 1e-4, "mu_init": 1e-3,
                     "warm_start_init_point": "yes"})
        self._slacks = S.shape
        return opti.to_function("mpc", [x0, u_prev, Xr, Ur, P, X, U, S, opti.lam_g],
                                [X, U, S, opti.lam_g, J])

    def solve(self, x, x_ref, u_ref, *, u_prev=None, P=None, warm=None) -> MPCSolution:
        """One MPC solve from the measured state ``x`` ``(n,)``.

        Args:
            x_ref: ``(N+1, n)`` reference states; u_ref: ``(N, r)`` reference inputs.
            u_prev: ``(r,)`` input applied during the last interval (rate limit; default 0).
            P: ``(n, n)`` terminal weight (default ``Q``).
            warm: the previous :class:`MPCSolution`, shifted by one sample as initial guess
                (default, and after a failed real-time step: the reference).
        """
        N, n, r = self.horizon, self.n, self.r
        x_ref, u_ref = np.asarray(x_ref, dtype=float), np.asarray(u_ref, dtype=float)
        if x_ref.shape != (N + 1, n) or u_ref.shape != (N, r):
            raise ShapeError(f"x_ref must be ({N + 1}, {n}) and u_ref ({N}, {r}); got "
                             f"{x_ref.shape} and {u_ref.shape}")
        u_prev = np.zeros(r) if u_prev is None else check_vector("u_prev", u_prev, r)
        P = self.Q if P is None else weight_matrix("P", P, n)
        x = as_float_array("x", x).ravel()
        if x.shape != (n,):
            raise ShapeError(f"x must be the measured state ({n},); got shape {x.shape}")
        check_finite("x", x)
        if warm is None or not (np.all(np.isfinite(warm.x)) and np.all(np.isfinite(warm.u))) \
                or (self.solver == "rti" and not warm.success):
            xg, ug = x_ref.T, u_ref.T       # no warm start from a failed or diverged solve
        else:
            xg = np.hstack([warm.x[1:].T, warm.x[-1:].T])
            ug = np.hstack([warm.u[1:].T, warm.u[-1:].T])
        start, cpu = time.perf_counter(), time.process_time()
        if self.solver == "rti":
            return self._solve_rti(x, u_prev, x_ref, u_ref, P, xg, ug, start, cpu)
        lg = 0.0 if warm is None or warm.multipliers.size == 0 else warm.multipliers
        X, U, S, L, J = self._function(x, u_prev, x_ref.T, u_ref.T, P, xg, ug,
                                       np.zeros(self._slacks), lg)
        elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
        stats = self._function.stats()
        return MPCSolution(x=np.array(X).T, u=np.array(U).reshape(r, N).T,
                           slack=float(np.max(np.array(S), initial=0.0)), objective=float(J),
                           multipliers=np.array(L), solve_time=elapsed, cpu_time=cpu,
                           iterations=int(stats.get("iter_count", -1)),
                           success=bool(stats.get("success", False)))

    def _solve_rti(self, x, u_prev, x_ref, u_ref, P, X, U, start, cpu) -> MPCSolution:
        ok = True
        for _ in range(self.max_iter):
            X, U, S, converged = self._rti.step(x, u_prev, x_ref.T, u_ref.T, P, X, U)
            if not converged:   # a warm start gone astray: one step from the reference
                X, U, S, converged = self._rti.step(x, u_prev, x_ref.T, u_ref.T, P,
                                                    x_ref.T, u_ref.T)
            ok = ok and converged
        elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
        E, V = X.T - x_ref, U.T - u_ref
        J = float(np.einsum("ki,ij,kj->", E[:-1], self.Q, E[:-1])
                  + np.einsum("ki,ij,kj->", V, self.R, V) + E[-1] @ P @ E[-1]
                  + self.soft_penalty * (np.sum(S) + np.sum(S ** 2)))
        return MPCSolution(x=X.T, u=U.T, slack=float(np.max(S, initial=0.0)), objective=J,
                           multipliers=np.zeros(0), solve_time=elapsed, cpu_time=cpu,
                           iterations=self.max_iter, success=ok)

    def follow(self, plan: Plan, *, tracker=None, u_final=None) -> MPCLaw:
        """A law ``law(k, x) -> u`` for :func:`~.closed_loop.closed_loop`: track ``plan``
        (same ``dt``), then hold its final state. Terminal weights: the cost-to-go of the
        TVLQR tracker of ``plan`` on this model with these ``Q``, ``R`` (``tracker``, computed
        if not given), which balances about the plan's end after it."""
        check_plan(plan)
        if abs(plan.dt - self.dt) > 1e-9 * self.dt:
            raise ParameterError(f"plan.dt must equal the controller's dt {self.dt}; got "
                                 f"{plan.dt}")
        if tracker is None:
            tracker = tvlqr(self._model, plan, Q=self.Q, R=self.R, Q_final="lqr",
                            u_final=u_final)
        return MPCLaw(self, plan, tracker)


@dataclass(frozen=True)
class MPCSolution:
    """One MPC solve: predicted states ``x`` ``(N+1, n)`` and inputs ``u`` ``(N, r)`` (``u[0]``
    is applied), largest state-bound slack, objective, IPOPT multipliers (for the next warm
    start; empty for the real-time iteration), wall and CPU time (s), iterations (IPOPT's, or
    SQP steps) and whether the solver converged (IPOPT) or every QP was solved (RTI)."""

    x: np.ndarray
    u: np.ndarray
    slack: float
    objective: float
    multipliers: np.ndarray
    solve_time: float
    cpu_time: float
    iterations: int
    success: bool


@dataclass
class MPCLaw:
    """``law(k, x) -> u``: MPC along a plan (reference window from sample ``k``), warm-started
    from its own last solution. Records every solve: ``solve_times`` and ``cpu_times`` (s),
    ``iterations``, ``converged``."""

    mpc: MPC
    plan: Plan
    tracker: object
    solve_times: list = field(default_factory=list)
    cpu_times: list = field(default_factory=list)
    iterations: list = field(default_factory=list)
    converged: list = field(default_factory=list)
    _last: MPCSolution | None = None
    _u: np.ndarray | None = None

    def __post_init__(self):
        if not isinstance(self.mpc, MPC):
            raise ParameterError(f"mpc must be an MPC; got {type(self.mpc).__name__}")
        check_plan(self.plan)

    def reset(self) -> None:
        """Forget the warm start, the last input and the records (a new run)."""
        self._last, self._u = None, None
        self.solve_times, self.cpu_times, self.iterations, self.converged = [], [], [], []

    def window(self, k: int):
        """``(x_ref (N+1, n), u_ref (N, r), P (n, n))`` from sample ``k``."""
        N, M = self.mpc.horizon, len(self.plan.u)
        idx = np.minimum(np.arange(k, k + N + 1), M)
        uidx = np.arange(k, k + N)
        u_end = self.tracker.u_final if self.tracker.u_final is not None else \
            np.zeros(self.mpc.r)
        u_ref = np.where((uidx < M)[:, None], self.plan.u[np.minimum(uidx, M - 1)], u_end)
        P = self.tracker.cost_to_go[min(k + N, M)]
        return self.plan.x[idx], u_ref, P

    def __call__(self, k: int, x) -> np.ndarray:
        x_ref, u_ref, P = self.window(k)
        sol = self.mpc.solve(np.asarray(x, dtype=float), x_ref, u_ref, u_prev=self._u, P=P,
                             warm=self._last)
        self._last, self._u = sol, sol.u[0]
        self.solve_times.append(sol.solve_time)
        self.cpu_times.append(sol.cpu_time)
        self.iterations.append(sol.iterations)
        self.converged.append(sol.success)
        return sol.u[0]

    def notify_applied(self, u) -> None:
        """The input actually applied (after an actuator's saturation), for the rate limit."""
        self._u = np.asarray(u, dtype=float).ravel()
