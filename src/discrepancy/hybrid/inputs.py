"""Measured inputs between their samples: how a simulation sees ``u(t)``.

A sampled input is only known at its sample times; what it did in between is a modelling
choice that a simulation must make explicitly, because it can matter as much as the model
(a lightly damped oscillator driven at ~10 samples per period is an example):

* ``"linear"``: straight lines between samples;
* ``"zoh"``: each sample held until the next (a digital-to-analogue converter's output);
* ``"bandlimited"``: the sampled signal's own continuous-time reconstruction (no frequency
  above the Nyquist frequency: Whittaker–Shannon interpolation with a Kaiser-windowed sinc,
  uniform sampling only).

:func:`input_law` gives ``u(τ)`` for adaptive solvers; :func:`stage_inputs` gives the input
at the stage times of fixed-step Runge–Kutta (``2·substeps + 1`` points per interval), the
form the compiled simulator and the output-error fit use.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..constraints import Options, check_argument
from ..data.trajectory import as_2d
from ..data.validation import as_float_array
from ..errors import DataError, ParameterError, ShapeError

#: how an input is held between its samples (``u_hold=``)
HOLDS = ("linear", "zoh", "bandlimited")
#: the hold of simulations and output-error fits when none is given
DEFAULT_HOLD = "linear"
#: fine-grid factor used to evaluate a band-limited input at arbitrary times
BANDLIMITED_OVERSAMPLING = 16


def check_hold(hold) -> str:
    """``hold`` if it is one of :data:`HOLDS`, else a :class:`~discrepancy.errors.ParameterError`.
    """
    check_argument("u_hold", hold, Options(HOLDS))
    return hold


def upsample_bandlimited(u: np.ndarray, factor: int, *, half_width: int = 32,
                         beta: float = 8.0) -> np.ndarray:
    """``u`` ``(m, r)`` sampled uniformly, reconstructed at ``factor`` times the rate:
    ``((m - 1) * factor + 1, r)`` values that pass through every sample.

    Each new value is a Kaiser-windowed sinc interpolation over ``2 * half_width`` samples
    (Whittaker–Shannon truncated smoothly), with the record mirrored at its ends; its
    error is about 1e-4 of the signal for content below 0.4 times the sampling rate and
    stays within ``half_width`` samples of the ends. Written here because scipy's
    ``resample_poly`` normalises its filter so that the result misses the samples."""
    m, r = u.shape
    if m < 2 or factor == 1:
        return u.copy()
    width = min(half_width, m - 1)
    extended = np.pad(u, ((width, width), (0, 0)), mode="reflect")
    windows = np.lib.stride_tricks.sliding_window_view(extended, 2 * width, axis=0)
    windows = windows[1:m]                                # (m - 1, r, 2w): around each gap
    taps = np.arange(-width + 1, width + 1)
    out = np.empty(((m - 1) * factor + 1, r))
    out[::factor] = u
    for j in range(1, factor):
        distance = taps - j / factor
        weight = np.sinc(distance) * np.i0(beta * np.sqrt(np.clip(
            1 - (distance / width) ** 2, 0, None))) / np.i0(beta)
        out[j::factor] = windows @ (weight / weight.sum())
    return out


def _uniform_step(t: np.ndarray) -> float:
    steps = np.diff(t)
    if not np.allclose(steps, steps[0], rtol=1e-6, atol=0):
        raise DataError("u_hold='bandlimited' needs uniformly sampled times; t has steps "
                        f"from {steps.min():.6g} to {steps.max():.6g}")
    return float(steps[0])


def input_law(u, t: np.ndarray, n_inputs: int, *, hold: str = "linear") -> Callable | None:
    """``u(τ) -> (r,)`` from an array sampled at ``t`` or a callable (checked at every call)."""
    if n_inputs == 0:
        if u is not None:
            raise ShapeError("u was given but the model has no inputs")
        return None
    if u is None:
        raise ShapeError(f"u is required: the model has {n_inputs} inputs")
    if callable(u):
        def law(tau):  # checked at every call: a law may change shape or go NaN later
            try:
                raw = u(tau)
            except Exception as e:
                raise ParameterError(f"u(t) raised {type(e).__name__} at t = {tau:.6g}: "
                                     f"{e}") from e
            value = as_float_array("u(t)", raw)
            if value.size != n_inputs or value.ndim > 2 or not np.all(np.isfinite(value)):
                raise ShapeError(f"u(t) must return {n_inputs} finite value(s), shape "
                                 f"({n_inputs},) or (1, {n_inputs}); at t = {tau:.6g} it "
                                 f"returned shape {value.shape}: {value.ravel()[:4]}")
            return value.reshape(n_inputs)
        law(float(t[0]))
        return law
    samples = as_2d("u", u, n_rows=len(t), n_cols=n_inputs, allow_1d=True)
    hold = check_hold(hold)
    if hold == "zoh":
        def held(tau):
            i = min(max(int(np.searchsorted(t, tau, side="right")) - 1, 0), len(t) - 1)
            return samples[i]
        return held
    if hold == "bandlimited":
        _uniform_step(t)
        fine = upsample_bandlimited(samples, BANDLIMITED_OVERSAMPLING)
        t, samples = np.linspace(t[0], t[-1], fine.shape[0]), fine
    return lambda tau: np.array([np.interp(tau, t, samples[:, j]) for j in range(n_inputs)])


def stage_inputs(u, t: np.ndarray, n_inputs: int, substeps: int, *,
                 hold: str = "linear") -> np.ndarray:
    """Inputs at the stage times of ``substeps`` RK4 steps per interval of ``t``:
    ``(len(t) - 1, 2 * substeps + 1, r)``, row ``j`` of interval ``k`` at
    ``t[k] + j (t[k+1] - t[k]) / (2 substeps)``.

    ``u``: samples ``(len(t), r)`` or a callable ``u(τ)``. A zero-order hold keeps ``u[k]``
    over the whole interval ``k``, its end included (the value jumps only after it)."""
    k, width = len(t) - 1, 2 * substeps + 1
    fraction = np.arange(width) / (width - 1)
    if callable(u):
        law = input_law(u, t, n_inputs)
        times = t[:-1, None] + fraction[None, :] * np.diff(t)[:, None]
        return np.array([[law(tau) for tau in row] for row in times]).reshape(k, width, -1)
    samples = as_2d("u", u, n_rows=len(t), n_cols=n_inputs, allow_1d=True)
    hold = check_hold(hold)
    if hold == "zoh":
        return np.repeat(samples[:-1, None, :], width, axis=1)
    if hold == "linear":
        return (samples[:-1, None, :] * (1 - fraction)[None, :, None]
                + samples[1:, None, :] * fraction[None, :, None])
    _uniform_step(t)
    fine = upsample_bandlimited(samples, width - 1)
    index = np.arange(k)[:, None] * (width - 1) + np.arange(width)[None, :]
    return fine[index]
