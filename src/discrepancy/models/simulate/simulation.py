"""Integrating a vectorised right-hand side ``f(x (k, n), u (k, r)) -> (k, n)``.

Adaptive methods are scipy's (``RK45``, ``DOP853``, ``LSODA``, ...), stepped here one step at
a time rather than through ``solve_ivp``, so that a budget can stop them: a right-hand side
that is discontinuous (a learned Coulomb term ``-F sign(v)``) or that blows up makes an
adaptive solver take millions of tiny steps, and instead of hanging the simulation stops
with a :class:`~discrepancy.errors.SimulationError` that says at what time and state, and
carries the trajectory computed so far. ``method="rk4"`` is classical fixed-step Runge-Kutta
on the output grid (``substeps`` steps per interval): bounded by construction, and the
method models with discontinuous terms use by default.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.integrate

from ...constraints import Integral, Interval, Options, Real, check_argument
from ...data.trajectory import as_times
from ...errors import ParameterError, ShapeError, SimulationError, describe
from ...hybrid.inputs import input_law, stage_inputs
from ...runge_kutta import runge_kutta_step

ADAPTIVE = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
METHODS = (*ADAPTIVE, "odeint", "rk4")
#: options passed on to scipy's adaptive solvers
SOLVER_OPTIONS = ("first_step", "max_step", "min_step", "jac", "jac_sparsity", "lband", "uband")
#: options passed on to scipy's ``odeint`` (PySINDy's ``integrator="odeint"``)
ODEINT_OPTIONS = ("mxstep", "hmax", "hmin", "h0", "tcrit", "mxordn", "mxords")
#: right-hand-side evaluations allowed per output sample (and at least MIN_EVALUATIONS)
EVALUATIONS_PER_SAMPLE = 500
MIN_EVALUATIONS = 100_000


class _Stop(Exception):
    def __init__(self, why: str, time: float, state):
        super().__init__(why)
        self.why, self.time, self.state = why, float(time), np.asarray(state, float).copy()


def _check_options(method, rtol, atol, substeps, max_evaluations, solver_kws):
    adaptive = isinstance(method, str) and method in ADAPTIVE
    odeint = isinstance(method, str) and method == "odeint"
    own = SOLVER_OPTIONS if adaptive else ODEINT_OPTIONS if odeint else ()
    unknown = sorted(set(solver_kws) - set(own))
    if unknown:
        raise ParameterError(f"simulate got unknown option(s) {unknown} for method "
                             f"{method!r}; valid: method, rtol, atol, u_hold, substeps, "
                             f"max_evaluations, compiled, integrator, integrator_kws, "
                             f"interpolator, interpolator_kws, {', '.join(SOLVER_OPTIONS)} (for "
                             f"adaptive methods), {', '.join(ODEINT_OPTIONS)} (for odeint)")
    check_argument("method", method, Options(METHODS))
    for name, value in (("rtol", rtol), ("atol", atol)):
        check_argument(name, value, Interval(Real, 0, closed="neither"))
    check_argument("substeps", substeps, Interval(Integral, 1, 10_000))
    check_argument("max_evaluations", max_evaluations, None, Interval(Integral, 1))


def check_options(options: dict) -> None:
    """Check :func:`integrate`'s keyword ``options`` (defaults for those not given) before
    work that depends on them, such as building a compiled stepper of ``substeps``."""
    import inspect

    defaults = {k: p.default for k, p in inspect.signature(integrate).parameters.items()
                if p.default is not p.empty}
    given = {**defaults, **options}
    _check_options(given["method"], given["rtol"], given["atol"], given["substeps"],
                   given["max_evaluations"], {k: v for k, v in options.items()
                                              if k not in defaults})


def integrate(rhs: Callable, x0, t, u=None, *, n_states: int, n_inputs: int,
              method: str = "LSODA", rtol: float = 1e-10, atol: float = 1e-10,
              u_hold: str = "linear", substeps: int = 4, max_evaluations: int | None = None,
              compiled: Callable | None = None, **solver_kws) -> np.ndarray:
    """Solve ``dx/dt = rhs(x, u(t))`` from ``x0`` and return the states at ``t`` ``(k, n)``.

    Args:
        method: an adaptive scipy method (``"LSODA"`` default), ``"odeint"`` (scipy's
            ``odeint``) or ``"rk4"`` (fixed steps, ``substeps`` per output interval, the input
            taken at the stage times).
        rtol, atol: tolerances of the adaptive methods.
        u_hold: ``"linear"``, ``"zoh"`` or ``"bandlimited"`` between input samples (see
            :mod:`discrepancy.hybrid.inputs`).
        max_evaluations: right-hand-side evaluations allowed (default ``500`` per output
            sample, at least 1e5).
        compiled: for ``"rk4"``, ``compiled(x0, stages, h) -> (k - 1, n)``, a compiled map of
            the same steps (see :mod:`discrepancy.models.simulate.fast_simulation`); ``None``
            steps in Python.

    Raises:
        SimulationError: (a ``ConvergenceError``) when the solution stops early: a
            non-finite right-hand side (blow-up), a failed step, or the evaluation budget
            spent (stiff or discontinuous dynamics); it says when and where, and
            ``.partial`` holds the states at the output times reached.
    """
    _check_options(method, rtol, atol, substeps, max_evaluations, solver_kws)
    x0 = np.asarray(x0, dtype=float).ravel()
    if x0.shape != (n_states,) or not np.all(np.isfinite(x0)):
        raise ShapeError(f"x0 must be {n_states} finite numbers (one per state); "
                         f"got shape {np.shape(x0)}")
    if np.ndim(t) != 1 or np.size(t) < 2:
        raise ShapeError(f"t must be a 1-D array of at least 2 output times (the first is the "
                         f"time of x0); got {describe(t)}")
    times = as_times("t", t, np.size(t))
    out = np.full((len(times), n_states), np.nan)
    out[0] = x0
    if method == "rk4":
        stages = stage_inputs(u, times, n_inputs, substeps, hold=u_hold) if n_inputs else \
            input_law(u, times, 0)
        if compiled is not None:
            return _checked(compiled(x0, stages, np.diff(times)), out, times)
    else:
        law = input_law(u, times, n_inputs, hold=u_hold)
    budget = max_evaluations or max(MIN_EVALUATIONS, EVALUATIONS_PER_SAMPLE * len(times))
    calls = [0]

    def f(tau, x, u_now):
        calls[0] += 1
        if calls[0] > budget:
            raise _Stop(f"the budget of {budget} right-hand-side evaluations is spent (stiff "
                        "or discontinuous dynamics; try method='rk4', or raise "
                        "max_evaluations)", tau, x)
        dx = rhs(x[None, :], None if u_now is None else u_now[None, :])[0]
        if not np.all(np.isfinite(dx)):
            raise _Stop("the right-hand side became non-finite (the solution diverges)",
                        tau, x)
        return dx

    if method == "odeint":
        return _odeint(f, law, times, out, rtol, atol, solver_kws)
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            if method == "rk4":
                _fixed_step(f, times, out, substeps, stages if n_inputs else None)
            else:
                _adaptive(lambda tau, x: f(tau, x, None if law is None else law(tau)),
                          times, out, method, rtol, atol, solver_kws)
    except _Stop as stop:
        _raise_stopped(stop.why, stop.time, stop.state, out, times)
    return out


def _raise_stopped(why, time, state, out, times):
    reached = int(np.sum(np.all(np.isfinite(out), axis=1)))
    raise SimulationError(
        f"simulation stopped at t = {time:.6g} of {times[-1]:.6g} at x = "
        f"{np.array2string(np.asarray(state, float), precision=4)}: {why}",
        time=time, state=state, partial=out[:reached], times=times[:reached]) from None


def _checked(states, out, times):
    """The compiled path's states ``(k - 1, n)`` after ``x0``, stopped at the first
    non-finite one as the stepped path would stop."""
    out[1:] = states
    bad = ~np.all(np.isfinite(out), axis=1)
    if bad.any():
        first = int(np.argmax(bad))
        out[first:] = np.nan
        _raise_stopped("the state became non-finite (the solution diverges)",
                       times[first - 1], out[first - 1], out, times)
    return out


def _adaptive(f, times, out, method, rtol, atol, solver_kws):
    solver = getattr(scipy.integrate, method)(f, times[0], out[0], times[-1], rtol=rtol,
                                              atol=atol, **solver_kws)
    i = 1
    while i < len(times):
        message = solver.step()
        if solver.status == "failed":
            raise _Stop(f"the solver failed ({message})", solver.t, solver.y)
        if times[i] <= solver.t or solver.status == "finished":
            dense = solver.dense_output()
            while i < len(times) and (times[i] <= solver.t or solver.status == "finished"):
                out[i] = dense(times[i])
                i += 1


def _odeint(f, law, times, out, rtol, atol, options):
    """scipy's ``odeint`` (ODEPACK's LSODA, PySINDy's ``integrator="odeint"``); stopped by
    the same budget and checks as the other methods."""
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            states, info = scipy.integrate.odeint(
                lambda x, tau: f(tau, x, None if law is None else law(tau)), out[0], times,
                rtol=rtol, atol=atol, full_output=True, **options)
    except _Stop as stop:
        _raise_stopped(stop.why, stop.time, stop.state, out, times)
    if info["message"] != "Integration successful.":
        reached = int(np.sum(info["tcur"] >= times[1:] - 1e-12 * abs(times[-1])))
        out[1:reached + 1] = states[1:reached + 1]
        _raise_stopped(f"odeint failed ({info['message']})", times[reached],
                       states[reached], out, times)
    return states


def _timed(f):
    """``f(t, x, u)`` as the ``rates(x, (t, u))`` of :func:`runge_kutta_step`."""
    return lambda x, stage: f(stage[0], x, stage[1])


def _fixed_step(f, times, out, substeps, stages):
    x = out[0].copy()
    for i in range(1, len(times)):
        h = (times[i] - times[i - 1]) / substeps
        tau = times[i - 1]
        s = None if stages is None else stages[i - 1]
        for j in range(substeps):
            u0, um, u1 = (None, None, None) if s is None else s[2 * j:2 * j + 3]
            x = runge_kutta_step(_timed(f), x, h, (tau, u0), (tau + h / 2, um), (tau + h, u1))
            tau += h
        out[i] = x
