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

from ..data.trajectory import as_2d, as_times
from ..errors import ParameterError, ShapeError, SimulationError, describe

ADAPTIVE = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
METHODS = (*ADAPTIVE, "rk4")
#: right-hand-side evaluations allowed per output sample (and at least MIN_EVALUATIONS)
EVALUATIONS_PER_SAMPLE = 500
MIN_EVALUATIONS = 100_000


class _Stop(Exception):
    def __init__(self, why: str, time: float, state):
        super().__init__(why)
        self.why, self.time, self.state = why, float(time), np.asarray(state, float).copy()


def input_law(u, t: np.ndarray, n_inputs: int, *, hold: str = "linear") -> Callable | None:
    """``u(τ) -> (r,)`` from an array sampled at ``t`` or a callable (checked at every call).

    ``hold="linear"`` interpolates between samples; ``"zoh"`` holds each sample until the next.
    """
    if n_inputs == 0:
        if u is not None:
            raise ShapeError("u was given but the model has no inputs")
        return None
    if u is None:
        raise ShapeError(f"u is required: the model has {n_inputs} inputs")
    if callable(u):
        def law(tau):  # checked at every call: a law may change shape or go NaN later
            value = np.asarray(u(tau), dtype=float)
            if value.size != n_inputs or value.ndim > 2 or not np.all(np.isfinite(value)):
                raise ShapeError(f"u(t) must return {n_inputs} finite value(s), shape "
                                 f"({n_inputs},) or (1, {n_inputs}); at t = {tau:.6g} it "
                                 f"returned shape {value.shape}: {value.ravel()[:4]}")
            return value.reshape(n_inputs)
        law(float(t[0]))
        return law
    samples = as_2d("u", u, n_rows=len(t), n_cols=n_inputs, allow_1d=True)
    if hold == "zoh":
        def held(tau):
            i = min(max(int(np.searchsorted(t, tau, side="right")) - 1, 0), len(t) - 1)
            return samples[i]
        return held
    if hold != "linear":
        raise ParameterError(f"u_hold must be 'linear' or 'zoh'; got {hold!r}")
    return lambda tau: np.array([np.interp(tau, t, samples[:, j]) for j in range(n_inputs)])


def _check_options(method, rtol, atol, substeps, max_evaluations):
    if method not in METHODS:
        raise ParameterError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    for name, value in (("rtol", rtol), ("atol", atol)):
        if not isinstance(value, (int, float)) or isinstance(value, bool) or \
                not np.isfinite(value) or value <= 0:
            raise ParameterError(f"{name} must be a positive number; got {value!r}")
    if not isinstance(substeps, (int, np.integer)) or isinstance(substeps, bool) or \
            not 1 <= substeps <= 10_000:
        raise ParameterError(f"substeps must be an integer in [1, 10000]; got {substeps!r}")
    if max_evaluations is not None and (not isinstance(max_evaluations, (int, np.integer))
                                        or max_evaluations < 1):
        raise ParameterError(f"max_evaluations must be a positive integer or None; got "
                             f"{max_evaluations!r}")


def integrate(rhs: Callable, x0, t, u=None, *, n_states: int, n_inputs: int,
              method: str = "LSODA", rtol: float = 1e-10, atol: float = 1e-10,
              u_hold: str = "linear", substeps: int = 4, max_evaluations: int | None = None,
              **solver_kws) -> np.ndarray:
    """Solve ``dx/dt = rhs(x, u(t))`` from ``x0`` and return the states at ``t`` ``(k, n)``.

    Args:
        method: an adaptive scipy method (``"LSODA"`` default) or ``"rk4"`` (fixed steps,
            ``substeps`` per output interval).
        rtol, atol: tolerances of the adaptive methods.
        u_hold: ``"linear"`` or ``"zoh"`` between input samples.
        max_evaluations: right-hand-side evaluations allowed (default ``500`` per output
            sample, at least 1e5).

    Raises:
        SimulationError (a ConvergenceError) when the solution stops early: a non-finite
        right-hand side (blow-up), a failed step, or the evaluation budget spent (stiff or
        discontinuous dynamics); it says when and where, and ``.partial`` holds the states
        at the output times reached.
    """
    _check_options(method, rtol, atol, substeps, max_evaluations)
    x0 = np.asarray(x0, dtype=float).ravel()
    if x0.shape != (n_states,) or not np.all(np.isfinite(x0)):
        raise ShapeError(f"x0 must be {n_states} finite numbers (one per state); "
                         f"got shape {np.shape(x0)}")
    if np.ndim(t) != 1 or np.size(t) < 2:
        raise ShapeError(f"t must be a 1-D array of at least 2 output times (the first is the "
                         f"time of x0); got {describe(t)}")
    times = as_times("t", t, np.size(t))
    law = input_law(u, times, n_inputs, hold=u_hold)
    budget = max_evaluations or max(MIN_EVALUATIONS, EVALUATIONS_PER_SAMPLE * len(times))
    out = np.full((len(times), n_states), np.nan)
    out[0] = x0
    calls = [0]

    def f(tau, x):
        calls[0] += 1
        if calls[0] > budget:
            raise _Stop(f"the budget of {budget} right-hand-side evaluations is spent (stiff "
                        "or discontinuous dynamics; try method='rk4', or raise "
                        "max_evaluations)", tau, x)
        dx = rhs(x[None, :], None if law is None else law(tau)[None, :])[0]
        if not np.all(np.isfinite(dx)):
            raise _Stop("the right-hand side became non-finite (the solution diverges)",
                        tau, x)
        return dx

    try:
        with np.errstate(over="ignore", invalid="ignore"):
            if method == "rk4":
                _fixed_step(f, times, out, substeps)
            else:
                _adaptive(f, times, out, method, rtol, atol, solver_kws)
    except _Stop as stop:
        reached = int(np.sum(np.all(np.isfinite(out), axis=1)))
        raise SimulationError(
            f"simulation stopped at t = {stop.time:.6g} of {times[-1]:.6g} at x = "
            f"{np.array2string(stop.state, precision=4)}: {stop.why}",
            time=stop.time, state=stop.state, partial=out[:reached],
            times=times[:reached]) from None
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


def _fixed_step(f, times, out, substeps):
    x = out[0].copy()
    for i in range(1, len(times)):
        h = (times[i] - times[i - 1]) / substeps
        tau = times[i - 1]
        for _ in range(substeps):
            k1 = f(tau, x)
            k2 = f(tau + h / 2, x + h / 2 * k1)
            k3 = f(tau + h / 2, x + h / 2 * k2)
            k4 = f(tau + h, x + h * k3)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            tau += h
        out[i] = x
