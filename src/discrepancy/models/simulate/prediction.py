"""k-step-ahead prediction: from every measured state, where the model is ``k`` samples later.

All starting points are integrated at once (RK4 with the input at its stage times, the
steps :meth:`~discrepancy.models.DiscrepancyModel.simulate` takes with ``method="rk4"``),
vectorised over the starts, so the cost is ``k`` steps of the whole record regardless of
its length. ``k = 1`` is one-step-ahead prediction; free simulation is the limit of
large ``k``.
"""
from __future__ import annotations

import numpy as np

from ...constraints import Integral, Interval, check_argument
from ...data.trajectory import as_2d, as_times
from ...errors import ShapeError
from ...hybrid.inputs import stage_inputs
from ...runge_kutta import runge_kutta_step


def predict_ahead(rhs, x, t, u, *, n_inputs: int, steps: int, u_hold: str,
                  substeps: int) -> np.ndarray:
    """States ``(m - steps, n)``: row ``i`` predicts ``x[i + steps]`` from ``x[i]``."""
    _check_steps(steps)
    check_argument("substeps", substeps, Interval(Integral, 1, 1000))
    m = x.shape[0]
    if m <= steps:
        raise ShapeError(f"x has {m} samples; predicting {steps} steps ahead needs more")
    times = as_times("t", t, m)
    stages = stage_inputs(u, times, n_inputs, substeps, hold=u_hold) if n_inputs else None
    h = np.diff(times)
    starts = m - steps
    state = x[:starts].copy()
    with np.errstate(over="ignore", invalid="ignore"):
        for j in range(steps):
            dt = (h[j:j + starts] / substeps)[:, None]
            for s in range(substeps):
                u0, um, u1 = (None, None, None) if stages is None else \
                    (stages[j:j + starts, 2 * s + i] for i in range(3))
                state = runge_kutta_step(rhs, state, dt, u0, um, u1)
    return state


def iterate_ahead(step, x, u, *, n_inputs: int, steps: int) -> np.ndarray:
    """The map's states ``(m - steps, n)``: row ``i`` is ``x[i]`` sent ``steps`` times
    through ``step(x, u) -> x_next`` with the inputs ``u[i], ..., u[i + steps - 1]``."""
    _check_steps(steps)
    m = x.shape[0]
    if m <= steps:
        raise ShapeError(f"x has {m} samples; predicting {steps} steps ahead needs more")
    if n_inputs:
        u = as_2d("u", u, n_cols=n_inputs, allow_1d=n_inputs == 1)
        if len(u) != m:
            raise ShapeError(f"u must have one row per sample of x ({m}); got {len(u)}")
    starts = m - steps
    state = x[:starts].copy()
    with np.errstate(over="ignore", invalid="ignore"):
        for j in range(steps):
            state = step(state, u[j:j + starts] if n_inputs else None)
    return state


def _check_steps(steps) -> None:
    check_argument("steps", steps, Interval(Integral, 1))


def checked_states(model, x, u):
    """``x`` as ``(m, n)`` after checking it and ``u`` against the fitted model's states and inputs
    (:class:`~discrepancy.errors.ShapeError` otherwise)."""
    x = as_2d("x", x, n_cols=model.n_states_, allow_1d=model.n_states_ == 1)
    if model.n_inputs_ and u is None:
        raise ShapeError(f"u is required: the model has inputs {model.input_names_}")
    if not model.n_inputs_ and u is not None:
        raise ShapeError("u was given but the model has no inputs")
    return x
