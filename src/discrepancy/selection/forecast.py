"""Batched forecasts: many coefficient sets from many origins, integrated at once.

Every (candidate, window) pair is one row of a batch of states; each row carries its own
coefficients, so one RK4 step of the batch (:func:`discrepancy.runge_kutta.runge_kutta_step`,
the input linear between samples) advances every candidate's forecast from every origin:
the cost is ``steps`` evaluations of the prior and of the union of the candidates' active
terms on ``candidates x windows x (n + 1)`` rows, whatever the record's length. A step
spans ``stride`` samples when the data's own time scale allows it
(:func:`choose_stride`); a discrete-time model iterates its map, one sample per step.

The score of a row is its mean scaled squared error (each state divided by its standard
deviation over the windows) over the leads 0..horizon, **after fitting the initial state**
to the window: ``n`` more rows per row carry perturbed initial states, and one
Gauss-Newton step on the accumulated normal equations gives the best start's error. Why:
a noisy origin state makes the forecast of a neutrally stable system (an oscillator)
drift in phase for ever, and a model that is merely less sensitive to its initial state
then beats the exact prior; with the start fitted, what remains is the model's error.
A forecast that leaves the data far behind (beyond :data:`BLOW_UP` standard deviations) or
turns non-finite is stopped and scores :data:`CAP` per lead from then on, so one divergent
candidate cannot make every mean infinite.

Written in numpy rather than with the compiled CasADi stepper of
:mod:`discrepancy.models.simulate.fast_simulation`: CasADi is an optional extra and the default fit
must not need it, and with every candidate and origin in one batch the per-step overhead
is shared (the default fit measured 2.5-3.5x the equation-error choice on 2500-10000
samples, ``benchmarks/bench_selection.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..expression_tape import compile_numpy_many
from ..runge_kutta import runge_kutta_step

#: scaled squared error given to a lead once a forecast has diverged (10 standard deviations)
CAP = 100.0
#: forecasts beyond this many standard deviations from the data's centre are stopped
BLOW_UP = 1e3
#: a step of ``stride`` samples is taken when ``stride * dt * rate`` stays below this
#: (``rate``: the data's fastest RMS rate of change over standard deviation)
STEP_LIMIT = 0.2
#: most samples per RK4 step (and the lag over which the rate is measured)
MAX_STRIDE = 8
#: relative size of the initial-state perturbations (of each state's scale)
PERTURBATION = 1e-6


@dataclass
class Origins:
    """Windows ready to forecast at a stride: ``x0`` ``(W, n)`` origin states, ``truth``
    ``(W, S + 1, n)`` the samples at leads ``0, s, 2s...`` (NaN past a window's end),
    ``h`` ``(W, S)`` step lengths, ``stages`` ``(W, S, 3, r)`` (the input at each step's
    start, middle and end; for a map its input) or None, ``fold`` ``(W,)``, ``scale``,
    ``centre`` ``(n,)``; ``stride``: samples per step."""

    x0: np.ndarray
    truth: np.ndarray
    h: np.ndarray
    stages: np.ndarray | None
    fold: np.ndarray
    scale: np.ndarray
    centre: np.ndarray
    stride: int = 1

    @property
    def n_windows(self) -> int:
        """Number of forecast windows ``W``."""
        return len(self.x0)

    @property
    def max_steps(self) -> int:
        """Most forecast steps ``S`` a window may take (of ``stride`` samples each)."""
        return self.h.shape[1]

    def steps_held(self) -> np.ndarray:
        """Steps each window has data for ``(W,)``."""
        return np.sum(np.all(np.isfinite(self.truth[:, 1:]), axis=2), axis=1)

    def subset(self, keep: np.ndarray, steps: int) -> Origins:
        """The windows ``keep`` cut to ``steps`` steps."""
        stages = None if self.stages is None else self.stages[keep, :steps]
        return Origins(self.x0[keep], self.truth[keep, :steps + 1], self.h[keep, :steps],
                       stages, self.fold[keep], self.scale, self.centre, self.stride)


def prepare(windows, setup, *, mean_square_rate=None, scale=None) -> Origins:
    """Origin states (the setup's smoothing at the origin, raw samples for maps and the weak
    form), the samples after them at the stride :func:`choose_stride` allows, padded to the
    longest window. ``mean_square_rate``: the mean squared derivative of each state over
    the data (the statistics' ``signal / count``), for the stride; default from the
    smoothing at the origins. ``scale``: each state's scale (default its standard
    deviation over the windows)."""
    smoothed = [_origin(w, setup) for w in windows]
    x0 = np.array([state for state, _ in smoothed])
    data = np.vstack([w.x[w.origin:] for w in windows])
    if scale is None:
        spread = data.std(axis=0)
        scale = np.where(spread > 0, spread, np.maximum(np.abs(data).max(axis=0), 1.0))
    if mean_square_rate is None and all(d is not None for _, d in smoothed):
        mean_square_rate = np.mean([d ** 2 for _, d in smoothed], axis=0)
    stride = choose_stride(windows, setup, mean_square_rate, scale)
    n, r = setup.n_states, setup.n_inputs
    W, S = len(windows), max(w.lead for w in windows) // stride
    truth = np.full((W, S + 1, n), np.nan)
    h = np.zeros((W, S))
    stages = np.zeros((W, S, 3, r)) if r else None
    for i, w in enumerate(windows):
        k = w.lead // stride
        at = w.origin + stride * np.arange(k + 1)
        truth[i, :k + 1] = w.x[at]
        h[i, :k] = np.diff(w.t[at])
        if stages is not None:
            stages[i, :k] = _stage_inputs(w, at, stride, setup.discrete_time)
    return Origins(x0, truth, h, stages, np.array([w.fold for w in windows]), scale,
                   data.mean(axis=0), stride)


def _stage_inputs(window, at, stride, discrete):
    """Inputs at each step's start, middle and end (linear between samples)."""
    u, t = window.u, window.t
    if discrete:
        return np.repeat(u[at[:-1], None, :], 3, axis=1)
    middle = (t[at[:-1]] + t[at[1:]]) / 2
    um = np.column_stack([np.interp(middle, t, u[:, j]) for j in range(u.shape[1])])
    return np.stack([u[at[:-1]], um, u[at[1:]]], axis=1)


def _origin(window, setup):
    """``(state, derivative or None)`` at a window's origin as the fit's method estimates
    them, from the samples within the method's reach of it (raw for maps, the weak form
    and windows too short to smooth)."""
    raw = window.x[window.origin], None
    method = setup.differentiation
    if setup.form.raw_origins:
        return raw
    reach = method.halo if method.halo is not None else window.origin
    lo, hi = window.origin - min(reach, window.origin), window.origin + reach + 1
    if hi - lo < method.min_samples or hi > window.filled:
        return raw
    xs, xd = method.smooth_and_differentiate(window.x[lo:hi], window.t[lo:hi])
    return xs[window.origin - lo], xd[window.origin - lo]


def choose_stride(windows, setup, mean_square_rate, scale) -> int:
    """Samples per RK4 step: the largest power of two (at most :data:`MAX_STRIDE`) whose
    step times the data's fastest rate (RMS derivative over standard deviation, per state)
    stays below :data:`STEP_LIMIT`; 1 for maps. Without derivatives (the weak form) the
    rate is that of the raw samples' changes over :data:`MAX_STRIDE` samples, which noise
    only makes larger (a shorter step)."""
    if setup.discrete_time:
        return 1
    dt = float(np.median(np.concatenate([np.diff(w.t) for w in windows])))
    if mean_square_rate is None:
        lag = MAX_STRIDE
        changes = [w.x[lag:w.filled] - w.x[:w.filled - lag] for w in windows
                   if w.filled > lag]
        if not changes:
            return 1
        mean_square_rate = np.mean(np.vstack(changes) ** 2, axis=0) / (lag * dt) ** 2
    rate = float(np.max(np.sqrt(np.asarray(mean_square_rate, float)) / scale))
    stride = 1
    while stride < MAX_STRIDE and 2 * stride * dt * rate <= STEP_LIMIT:
        stride *= 2
    return stride


class BatchModel:
    """``f_m(x, u) + Θ_active(x, u) C_b`` for a batch of rows, each with its coefficients
    ``C`` ``(B, n, p)`` (only the columns some row uses are evaluated)."""

    def __init__(self, setup, coef: np.ndarray):
        self.setup = setup
        used = np.flatnonzero(np.any(coef != 0, axis=(0, 1)))
        functions = setup.library.user_functions()
        names = setup.variable_names
        # one tape for all the terms: a subexpression they share is computed once
        self.terms = compile_numpy_many([setup.library.feature_expressions_[j] for j in used],
                                        names, functions) if len(used) else None
        self.coef = np.ascontiguousarray(coef[:, :, used].transpose(0, 2, 1))   # (B, q, n)

    def __call__(self, x: np.ndarray, u: np.ndarray | None) -> np.ndarray:
        """(Called inside ``np.errstate(all="ignore")``: a wild row is caught afterwards.)"""
        out = self.setup.prior.unchecked(x, u)
        if self.terms is not None:
            z = x if u is None else np.concatenate((x, u), axis=1)
            theta = np.column_stack(self.terms(z))
            out = out + np.einsum("bq,bqn->bn", theta, self.coef)
        return out


@dataclass
class Scores:
    """Per row: ``score`` (mean scaled squared error over the leads held, initial state
    fitted) and ``lead`` ``(B, S + 1)``: the scaled squared error at each lead from the
    origin as given (NaN past a window's end)."""

    score: np.ndarray
    lead: np.ndarray
    gain: np.ndarray | None = None


def forecast_scores(setup, origins: Origins, coef: np.ndarray, window: np.ndarray,
                    steps: int) -> Scores:
    """Forecasts of rows ``b`` from window ``window[b]`` with coefficients ``coef[b]``
    ``(n, p)`` for ``steps`` steps, scored with the initial state fitted (module doc)."""
    score, lead, _, gain = _run(setup, origins, coef, window, steps, origins.x0[window])
    return Scores(score, lead, gain)


def refine_origins(setup, origins: Origins, steps: int, coef: np.ndarray) -> Origins:
    """The origins with the state a reference model (``coef`` ``(n, p)``: the prior, or a
    better-forecasting correction) fits best over their first ``steps`` steps (one
    Gauss-Newton step from the smoothed state): over a short stretch every sensible model
    agrees with it, and the start is then close enough for one linear step per candidate
    over the whole horizon."""
    everything = np.arange(origins.n_windows)
    _, _, delta, _ = _run(setup, origins, np.repeat(coef[None], origins.n_windows, axis=0),
                          everything, steps, origins.x0)
    return Origins(origins.x0 + delta, origins.truth, origins.h, origins.stages,
                   origins.fold, origins.scale, origins.centre, origins.stride)


def _run(setup, origins, coef, window, steps, x0):
    n = setup.n_states
    B = len(window)
    group = np.repeat(np.arange(B), n + 1)               # base row, then n perturbed ones
    model = BatchModel(setup, coef[group])
    nudge = PERTURBATION * origins.scale
    start = x0[group] + np.tile(np.vstack([np.zeros(n), np.diag(nudge)]), (B, 1))
    fit = _NormalEquations(B, n)
    lead = np.full((B, steps + 1), np.nan)
    gain = np.full((B, steps + 1), np.nan)
    x, alive = start.copy(), np.ones(B, bool)
    with np.errstate(all="ignore"):
        for k in range(steps + 1):
            if k:
                x = _step(model, x, origins, window[group], k - 1, setup.discrete_time)
                wild = ~np.all(np.isfinite(x), axis=1) | \
                    np.any(np.abs(x - origins.centre) > BLOW_UP * origins.scale, axis=1)
                alive &= ~wild.reshape(B, n + 1)[:, 0]
                x[wild] = start[wild]          # keeps the batch finite; the row is dead
            truth = origins.truth[window, k]
            held = np.isfinite(truth[:, 0])
            states = x.reshape(B, n + 1, n)
            error = (states[:, 0] - truth) / origins.scale
            jacobian = (states[:, 1:] - states[:, :1]).transpose(0, 2, 1) / \
                (nudge / origins.scale)[None, None, :] / origins.scale[None, :, None]
            lead[:, k] = np.where(alive, np.minimum(np.mean(error ** 2, axis=1), CAP), CAP)
            gain[:, k] = np.sqrt(np.mean(jacobian ** 2, axis=(1, 2)) * n)
            fit.add(np.nan_to_num(error), np.nan_to_num(jacobian), held & alive)
    score, delta = fit.fitted_mean_square()
    seen = np.isfinite(lead)
    plain = np.where(seen, lead, 0).sum(axis=1) / np.maximum(seen.sum(axis=1), 1)
    score[~alive] = plain[~alive]
    delta[~alive] = 0.0
    return score, lead, delta * origins.scale, gain


class _NormalEquations:
    """Running ``JᵀJ``, ``Jᵀe``, ``eᵀe`` of each row's scaled errors ``e`` against its
    initial-state sensitivities ``J``; the fitted residual needs no stored trajectory."""

    def __init__(self, B: int, n: int):
        self.G, self.b = np.zeros((B, n, n)), np.zeros((B, n))
        self.ss, self.count = np.zeros(B), np.zeros(B)
        self.n = n

    def add(self, error, jacobian, use) -> None:
        w = use[:, None]
        e, J = error * w, jacobian * w[:, :, None]
        self.G += np.einsum("bik,bil->bkl", J, J)
        self.b += np.einsum("bik,bi->bk", J, e)
        self.ss += np.einsum("bi,bi->b", e, e)
        self.count += use * self.n

    def fitted_mean_square(self) -> np.ndarray:
        ridge = 1e-12 * np.trace(self.G, axis1=1, axis2=2)[:, None, None] * np.eye(self.n)
        delta = np.linalg.solve(self.G + ridge + 1e-300 * np.eye(self.n), self.b[..., None])
        ss = self.ss - np.einsum("bk,bk->b", self.b, delta[..., 0])
        return np.maximum(ss, 0) / np.maximum(self.count, 1), -delta[..., 0]


def _step(model, x, origins, window, k, discrete):
    stages = None if origins.stages is None else origins.stages[window, k]
    if discrete:
        return model(x, None if stages is None else stages[:, 0])
    h = origins.h[window, k][:, None]
    u0, um, u1 = (None, None, None) if stages is None else \
        (stages[:, 0], stages[:, 1], stages[:, 2])
    return runge_kutta_step(model, x, h, u0, um, u1)
