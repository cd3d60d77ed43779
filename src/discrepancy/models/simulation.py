"""Integrating a vectorised right-hand side ``f(x (k, n), u (k, r)) -> (k, n)`` with scipy."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp

from ..data.trajectory import as_2d, as_times
from ..errors import ConvergenceError, ParameterError, ShapeError, describe


class _Diverged(Exception):
    def __init__(self, time, state):
        super().__init__(time)
        self.time, self.state = float(time), np.array2string(np.asarray(state), precision=4)


def input_law(u, t: np.ndarray, n_inputs: int, *, hold: str = "linear") -> Callable | None:
    """``u(τ) -> (r,)`` from an array sampled at ``t`` or a callable (checked once).

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


def integrate(rhs: Callable, x0, t, u=None, *, n_states: int, n_inputs: int,
              method: str = "LSODA", rtol: float = 1e-10, atol: float = 1e-10,
              u_hold: str = "linear", **solver_kws) -> np.ndarray:
    """Solve ``dx/dt = rhs(x, u(t))`` from ``x0`` and return the states at ``t`` ``(k, n)``.

    Raises ConvergenceError when the solver stops early (blow-up, stiffness), naming
    the time reached, instead of returning a partial trajectory.
    """
    x0 = np.asarray(x0, dtype=float).ravel()
    if x0.shape != (n_states,) or not np.all(np.isfinite(x0)):
        raise ShapeError(f"x0 must be {n_states} finite numbers (one per state); "
                         f"got shape {np.shape(x0)}")
    if np.ndim(t) != 1 or np.size(t) < 2:
        raise ShapeError(f"t must be a 1-D array of at least 2 output times (the first is the "
                         f"time of x0); got {describe(t)}")
    times = as_times("t", t, np.size(t))
    law = input_law(u, times, n_inputs, hold=u_hold)

    def f(tau, x):
        dx = rhs(x[None, :], None if law is None else law(tau)[None, :])[0]
        if not np.all(np.isfinite(dx)):
            raise _Diverged(tau, x)
        return dx

    try:
        with np.errstate(over="ignore", invalid="ignore"):
            sol = solve_ivp(f, (times[0], times[-1]), x0, t_eval=times, method=method,
                            rtol=rtol, atol=atol, **solver_kws)
    except _Diverged as e:
        raise ConvergenceError(f"integration stopped at t = {e.time:.6g} of {times[-1]:.6g}: "
                               f"the right-hand side became non-finite at x = {e.state} "
                               "(the solution diverges)") from None
    if sol.status != 0 or sol.y.shape[1] != len(times):
        reached = sol.t[-1] if sol.t.size else times[0]
        raise ConvergenceError(f"integration stopped at t = {reached:.6g} of {times[-1]:.6g}: "
                               f"{sol.message}")
    return sol.y.T
