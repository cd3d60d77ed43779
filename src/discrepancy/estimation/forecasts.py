"""Held-out forecasts from filtered states: how a model is scored for choosing its terms.

One-step innovations judge a model where its filter corrects it at every sample; terms
that matter over a longer time (a weak damping, a slow drift) barely change them, and a
disturbance state with a larger intensity can absorb what a missing term would explain.
So supports are compared by forecasts: from every held-out sample the model runs freely
from its filtered state (the disturbance held at its estimate) for ``horizon`` samples
with the measured input, and the squared output errors, scaled by each output's variance,
are averaged over the leads. All origins of a record run at once (CasADi ``map`` of a
``mapaccum`` of the RK4 step).
"""
from __future__ import annotations

import numpy as np

from ..hybrid.casadi_form import casadi_module, rk4_step

#: origins per compiled call
ORIGINS = 256
#: the horizon is where the outputs' autocorrelation first falls below this
DECORRELATION = 0.5


def forecast_horizon(records, low: int = 5, high: int = 200) -> int:
    """Samples over which the outputs decorrelate (autocorrelation below 0.5), the
    smallest over outputs and records, within ``[low, high]``: a system's own time scale."""
    lags = []
    for rec in records:
        for j in range(rec.k):
            v = rec.y[rec.w[:, j] > 0, j]
            v = v - v.mean()
            if len(v) < 3 * low or not np.any(v):
                continue
            spectrum = np.fft.rfft(v, 2 * len(v))
            acf = np.fft.irfft(spectrum * np.conj(spectrum))[:len(v)]
            below = np.flatnonzero(acf / acf[0] < DECORRELATION)
            lags.append(int(below[0]) if len(below) else high)
    return int(np.clip(min(lags) if lags else low, low, high))


class Forecaster:
    """Forecasts of one support's model (``likelihood.f``) over ``horizon`` samples."""

    def __init__(self, likelihood, horizon: int, substeps: int):
        ca = casadi_module()
        N, r, f = likelihood.N, likelihood.r, likelihood.f
        self.empty = f.size1_in(2) == 0
        if self.empty:                   # the prior alone: a dummy parameter keeps one call
            x, u, p = ca.SX.sym("x", N), ca.SX.sym("u", r), ca.SX.sym("p", 1)
            f = ca.Function("f", [x, u, p], [f(x, u, ca.SX(0, 1))])
        step = rk4_step(f, N, r, substeps, n_parameters=f.size1_in(2))
        self.horizon, self.width, self.N = horizon, step.size1_in(1), N
        self.run = step.mapaccum("forecast", horizon).map(ORIGINS)

    def errors(self, filtered_x, record, coef_support, measurement, scale) -> np.ndarray:
        """Mean scaled squared output error over leads ``1..horizon`` from every origin
        ``i`` with ``i + horizon < m`` ``(m - horizon,)`` (missing outputs skipped)."""
        K, m = self.horizon, record.m
        origins = np.arange(m - K)
        columns = record.data()[:, 2 * record.k:2 * record.k + self.width].T   # (width, m)
        steps = record.data()[:, -1]
        index = origins[:, None] + np.arange(K)[None, :]                     # (o, K)
        out = np.empty(len(origins))
        for start in range(0, len(origins), ORIGINS):
            chunk = index[start:start + ORIGINS]
            count = len(chunk)
            pad = np.vstack([chunk, np.repeat(chunk[-1:], ORIGINS - count, axis=0)])
            x0 = filtered_x[pad[:, 0]].T
            U = columns[:, pad.ravel()]
            h = steps[pad.ravel()][None, :]
            coef = [0.0] if self.empty else coef_support
            states = np.asarray(self.run(x0, U, h, coef))                    # (N, K * O)
            states = states.reshape(self.N, ORIGINS, K).transpose(1, 2, 0)[:count]
            predicted = measurement.values(states.reshape(-1, self.N)).reshape(count, K, -1)
            target = record.y[chunk + 1]
            seen = record.w[chunk + 1]
            err = ((predicted - target) / scale) ** 2 * seen
            out[start:start + count] = err.sum(axis=(1, 2)) / np.maximum(seen.sum(axis=(1, 2)), 1)
        return out
