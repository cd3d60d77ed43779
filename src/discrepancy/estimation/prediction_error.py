"""Prediction-error fits: the discrepancy and the noise levels that make the hybrid model,
run inside an extended Kalman filter, predict each next measurement best.

Output error simulates the model freely from its initial state, so anything the model does
not contain (a push, a load change, process noise, chaos) drives the simulation away and
the fit bends the discrepancy to explain it. Here the filter corrects the state at every
sample, so only the one-step innovations ``e_k = y_k - h(x_{k|k-1})`` count: the fit
minimises their negative log-likelihood ``Σ ½ (e_kᵀ S_k⁻¹ e_k + log det S_k)`` over the
coefficients, the process noise per state (per √s) and the measurement noise per output,
with exact gradients through the filter (:mod:`~discrepancy.estimation.likelihood`) and
scipy's L-BFGS-B. Unmeasured disturbances are states of their own
(:mod:`~discrepancy.estimation.disturbances`) whose random-walk intensity is fitted too.
Terms are chosen along a path of supports (:mod:`~discrepancy.estimation.support_path`).
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import scipy.optimize

from .likelihood import InnovationLikelihood, LikelihoodRecord
from .records import FilterRecord, assemble_result
from .support_path import block_means, mean_and_se

#: ridge on the scaled coefficients while supports are compared
RIDGE = 1e-5
#: samples at the start of each record whose innovations do not count (the filter settles)
BURN_IN = 20
#: the fitted noise levels stay within these factors of their starting values
NOISE_RANGE = (1e-6, 1e4)


class PredictionErrorProblem:
    """The pieces of one fit: records, noise layout, scales, and one likelihood per support.

    Args:
        setup: the model's set-up.
        measurement: what ``y`` measures.
        equations: the disturbed equations.
        records: :class:`FilterRecord` objects (built with ``spec``).
        spec: the settings records and likelihoods share (``dynamics``, ``measurement``,
            ``substeps``, ``u_hold``, ``R``).
        q_free, r_free: which noise levels are fitted.
        q0, r0: their values (starting or fixed).
    """

    def __init__(self, setup, measurement, equations, records, spec, q_free, r_free, q0, r0):
        self.setup, self.measurement, self.equations = setup, measurement, equations
        self.records, self.spec = records, spec
        self.n, self.p, self.N = setup.n_states, setup.n_features, spec.dynamics.n
        self.q_free, self.r_free = q_free, r_free
        self.noise0 = np.concatenate([q0, r0])
        self.coef_scale = np.ones((self.n, self.p))
        self._likelihoods, self._objectives, self._forecasters = {}, {}, {}
        from .forecasts import forecast_horizon

        self.horizon = forecast_horizon(records)
        y = np.vstack([rec.y for rec in records])
        seen = np.vstack([rec.w for rec in records]) > 0
        self.y_scale = np.array([max(float(np.std(y[seen[:, j], j])), 1e-12)
                                 for j in range(y.shape[1])])
        self.beliefs = [rec.initial_belief(spec, None, None) for rec in records]
        self.data = [rec.data() for rec in records]

    # ---------------------------------------------------------------- pieces
    def likelihood(self, support) -> InnovationLikelihood:
        """The :class:`~discrepancy.estimation.likelihood.InnovationLikelihood` of the terms
        ``support`` (``(n, p)`` bool), built once per support and cached."""
        key = support.tobytes()
        if key not in self._likelihoods:
            self._likelihoods[key] = InnovationLikelihood(
                self.setup, self.measurement, self.equations, self.spec.substeps, support)
        return self._likelihoods[key]

    def _objective(self, support, rows):
        key = (support.tobytes(), tuple(r.tobytes() for r in rows))
        if key not in self._objectives:
            lik = self.likelihood(support)
            self._objectives[key] = lik.objective(self._likelihood_records(rows))
        return self._objectives[key]

    def _likelihood_records(self, rows):
        return [LikelihoodRecord(d, x0, P0, w) for d, (x0, P0), w in
                zip(self.data, self.beliefs, rows, strict=True)]

    def split(self, noise):
        """``(q, r)`` from ``noise`` ``(N + k,)``: the process-noise levels of the ``N`` filter
        states (per √s) and the measurement-noise standard deviations of the ``k`` outputs."""
        return noise[:self.N], noise[self.N:]

    # ---------------------------------------------------------------- fitting
    def solve(self, support, coef, noise, rows, ridge, *, max_iterations: int = 300):
        """Minimise the innovations' mean negative log-likelihood on ``rows`` (a weight per
        sample of each record) over the coefficients of ``support`` and the free noise
        levels, from ``coef`` ``(n, p)`` and ``noise`` ``(N + k,)``; returns ``(coef, noise,
        value)``."""
        J = self._objective(support, rows)
        scale = self.coef_scale[support]
        free = np.concatenate([self.q_free, self.r_free])
        base = self.noise0[free]
        start = np.concatenate([coef[support] / scale, np.log(np.clip(noise[free], base *
                                                                       NOISE_RANGE[0], None))])
        bounds = [(None, None)] * int(support.sum()) + \
            [(np.log(b * NOISE_RANGE[0]), np.log(b * NOISE_RANGE[1])) for b in base]
        n_coef = int(support.sum())

        def unpack(theta):
            c = theta[:n_coef] * scale
            full = noise.copy()
            full[free] = np.exp(theta[n_coef:])
            return c, full

        def value_and_gradient(theta):
            c, full = unpack(theta)
            q, r = self.split(full)
            value, grad = J(c, q, r)
            value, grad = float(value), np.asarray(grad).ravel()
            if not np.isfinite(value) or not np.all(np.isfinite(grad)):
                return 1e10, np.zeros_like(theta)
            value += ridge * float(theta[:n_coef] @ theta[:n_coef])
            g = np.concatenate([grad[:n_coef] * scale + 2 * ridge * theta[:n_coef],
                                grad[n_coef:][free] * full[free]])
            return value, g

        with np.errstate(all="ignore"):
            result = scipy.optimize.minimize(value_and_gradient, start, jac=True,
                                             method="L-BFGS-B", bounds=bounds,
                                             options={"maxiter": max_iterations})
        c, full = unpack(result.x)
        out = np.zeros((self.n, self.p))
        out[support] = c
        return out, full, float(result.fun)

    # ---------------------------------------------------------------- scoring
    def per_sample(self, support, coef, noise) -> list[np.ndarray]:
        """Negative log-likelihood of every sample of every record ``(m,)`` (the filter
        over each whole record with these parameters)."""
        lik = self.likelihood(support)
        q, r = self.split(noise)
        out = []
        for d, (x0, P0) in zip(self.data, self.beliefs, strict=True):
            steps, _ = lik.run(LikelihoodRecord(d, x0, P0, None), coef, q, r)
            out.append(steps[:, lik.sizes["out"] - self.N ** 2 - 1])
        return out

    def score(self, support, coef, noise, rows) -> tuple[float, float, np.ndarray]:
        """Mean negative log-likelihood per sample on ``rows``, its block standard error
        and the block means."""
        values = self.per_sample(support, coef, noise)
        blocks = block_means([v[w > 0] for v, w in zip(values, rows, strict=True)])
        return (*mean_and_se(blocks), blocks)

    def forecast_score(self, support, coef, noise, rows) -> tuple[float, float, np.ndarray]:
        """Mean scaled squared forecast error over ``horizon`` samples from the filtered
        states at every origin in ``rows`` (see :mod:`~discrepancy.estimation.forecasts`),
        its block standard error and the block means."""
        from .forecasts import Forecaster

        key = support.tobytes()
        if key not in self._forecasters:
            self._forecasters[key] = Forecaster(self.likelihood(support), self.horizon,
                                                self.spec.substeps)
        forecaster, values = self._forecasters[key], []
        for i, (rec, w) in enumerate(zip(self.records, rows, strict=True)):
            x = self.filtered(support, coef, noise, i, check=False).x
            errors = forecaster.errors(x, rec, coef[support], self.measurement, self.y_scale)
            values.append(errors[w[:len(errors)] > 0])
        return (*mean_and_se(block_means(values)), block_means(values))

    def filtered(self, support, coef, noise, i: int = 0, *, check: bool = True):
        """The :class:`~discrepancy.estimation.FilterResult` of record ``i``."""
        lik = self.likelihood(support)
        q, r = self.split(noise)
        x0, P0 = self.beliefs[i]
        out, carries = lik.run(LikelihoodRecord(self.data[i], x0, P0, None), coef, q, r)
        names = (list(self.spec.dynamics.state_names), self.measurement.names)
        if not check:           # a diverging candidate scores infinity, it does not raise
            out, carries = np.nan_to_num(out, nan=1e100), np.nan_to_num(carries, nan=1e100)
        return assemble_result(names, self.records[i], x0, P0, out, carries)

    def set_coef_scale(self, states: list[np.ndarray]):
        """Scale of each coefficient: its equation's derivative scale over its column's
        RMS along ``states`` (smoothed estimates per record), so that scaled sizes compare
        across terms."""
        theta_ms, rate_ms = [], []
        for x, rec in zip(states, self.records, strict=True):
            z = x[:, :self.n] if rec.u is None else np.hstack([x[:, :self.n], rec.u])
            theta_ms.append(np.mean(self.setup.library.transform(z) ** 2, axis=0))
            rate_ms.append(np.mean((np.diff(x[:, :self.n], axis=0) / rec.h[:, None]) ** 2,
                                   axis=0))
        theta = np.sqrt(np.mean(theta_ms, axis=0))
        rate = np.sqrt(np.mean(rate_ms, axis=0))
        rate = np.where(rate > 0, rate, max(float(rate.max()), 1.0))
        self.coef_scale = rate[:, None] / np.where(theta > 0, theta, 1.0)[None, :]

    def importance(self, coef) -> np.ndarray:
        """``(n, p)``: the size of each coefficient of ``coef`` ``(n, p)`` in scaled units
        (``|coef| / coef_scale``, see :meth:`set_coef_scale`), so terms compare."""
        return np.abs(coef) / self.coef_scale


def record_spec(dynamics_like, measurement, substeps, u_hold, r0):
    """The settings :class:`FilterRecord` reads, for a fit that has no filter object."""
    return SimpleNamespace(dynamics=dynamics_like, measurement=measurement,
                           substeps=substeps, u_hold=u_hold, R=np.diag(r0 ** 2))


def rows_of(records, holdout: float | None):
    """``(training, held-out)`` weights per record (the first ``BURN_IN`` samples in
    neither); ``holdout=None``: every sample after the burn-in, and no held-out rows."""
    train, test = [], []
    for rec in records:
        w = np.zeros(rec.m)
        w[min(BURN_IN, rec.m // 10):] = 1.0
        w *= rec.w.max(axis=1)                       # a sample with nothing measured
        if holdout is None:
            train.append(w)
            test.append(np.zeros(rec.m))
            continue
        cut = int(round(rec.m * (1 - holdout)))
        head = w.copy()
        head[cut:] = 0.0
        train.append(head)
        test.append(w - head)
    return train, test


def measurement_noise_guess(records) -> np.ndarray:
    """A std per output from the third differences of the measured samples (white noise
    gives ``var(Δ³y) = 20 σ²``; a smooth signal sampled finely adds little), by the
    median absolute deviation so that jumps do not count."""
    stds = []
    for j in range(records[0].k):
        parts = [np.diff(rec.y[rec.w[:, j] > 0, j], 3) for rec in records]
        d3 = np.concatenate([p for p in parts if len(p)]) if any(len(p) for p in parts) \
            else np.zeros(1)
        spread = 1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20)
        level = max(float(np.std(np.concatenate([rec.y[:, j] for rec in records]))), 1e-12)
        stds.append(max(spread, 1e-4 * level))
    return np.array(stds)


def check_records(records):
    """Raise :class:`~discrepancy.errors.DataError` when a record is shorter than
    ``4 * BURN_IN`` samples (the first ``BURN_IN`` only let the filter settle)."""
    for rec in records:
        if rec.m < 4 * BURN_IN:
            from ..errors import DataError
            raise DataError(f"a record of {rec.m} samples is too short for a prediction-error "
                            f"fit (at least {4 * BURN_IN}: the first {BURN_IN} let the filter "
                            "settle)")


__all__ = ["FilterRecord", "PredictionErrorProblem", "check_records", "measurement_noise_guess",
           "record_spec", "rows_of"]
