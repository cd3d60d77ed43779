"""Discrete-time models, maps ``x[k+1] = f_m(x[k], u[k]) + g(x[k], u[k])``: their
simulation (their regression rows are :mod:`discrepancy.fitting.discrete`)."""
from __future__ import annotations

import numpy as np

from ...data.validation import check_array
from ...errors import ConvergenceError, ParameterError, ShapeError
from ...resources import check_memory, n_bytes


def iterate(step, x0, steps, u, n_states: int, n_inputs: int, *,
            stop_condition=None) -> np.ndarray:
    """States ``(steps, n)`` of ``x[k+1] = step(x[k], u[k])`` from ``x0`` (row 0 is ``x0``).

    ``steps``: the number of states to return (an int), or an array of that length (its
    values are not used: a map has no time). ``u``: ``(steps, r)`` (row ``k`` acts on step
    ``k``; the last row is not used) or a callable of the step index. ``stop_condition(x)``:
    the run ends at the first new state ``x`` ``(n,)`` for which it is true (PySINDy's).
    """
    if stop_condition is not None and not callable(stop_condition):
        raise ParameterError(f"stop_condition must be a callable stop_condition(x) -> bool; "
                             f"got {type(stop_condition).__name__}")
    n_steps = len(steps) if np.ndim(steps) == 1 else steps
    if not isinstance(n_steps, (int, np.integer)) or isinstance(n_steps, bool) or n_steps < 1:
        raise ParameterError(f"t must be the number of steps (an integer >= 1) or an array of "
                             f"that length for a discrete-time model; got {steps!r:.60}")
    check_memory(f"the simulation's output ({n_steps} steps x {n_states} states)",
                 n_bytes((n_steps, n_states)), "Ask for fewer steps, or simulate in pieces "
                 "(each starting from the last state of the one before)")
    x0 = check_array("x0", np.reshape(x0, (1, -1)), n_cols=n_states)
    if n_inputs and u is None:
        raise ShapeError(f"u is required: the model has {n_inputs} inputs")
    if not n_inputs and u is not None:
        raise ShapeError("u was given but the model has no inputs")
    if n_inputs and not callable(u):
        u = check_array("u", u, n_rows=int(n_steps), n_cols=n_inputs, allow_1d=True)
    out = np.empty((int(n_steps), n_states))
    out[0] = x0[0]
    for k in range(int(n_steps) - 1):
        uk = None if not n_inputs else (np.reshape(u(k), (1, n_inputs)) if callable(u)
                                         else u[k:k + 1])
        out[k + 1] = step(out[k:k + 1], uk)[0]
        if not np.all(np.isfinite(out[k + 1])):
            raise ConvergenceError(f"the map diverged at step {k + 1} (x = {out[k]})")
        if stop_condition is not None and stop_condition(out[k + 1].copy()):
            return out[:k + 2]
    return out
