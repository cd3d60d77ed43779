"""Output-error fits: the discrepancy and the unmeasured states from what is measured.

When only some states (or functions of them) are recorded, the derivative of every state
is not available and the usual regression cannot be formed. Here the hybrid model is
simulated from an estimated initial state with the measured input (RK4 at the input's
stage times, see :mod:`discrepancy.models.outputs.shooting`) and its coefficients and initial
states are chosen to minimise the simulation error of the recorded outputs (Gauss–Newton
with a trust region: scipy's ``least_squares`` on exact CasADi derivatives).

Sparsity: the whole library is fitted first (with a small ridge on coefficients scaled to
their equation), then terms are removed one at a time, the least important first, each
support refitted. With ``threshold="auto"`` the supports are fitted on the first part of
every record and scored by how well they forecast the rest (free simulation of the held-out
end); the sparsest support within ``tolerance`` of the best forecast is refitted on all the
data. A fixed threshold instead drops terms whose coefficients stay below it.
"""
from __future__ import annotations

import copy
import warnings

import numpy as np
import scipy.optimize

from ...data.trajectory import as_trajectories
from ...errors import DataError, ParameterError, ShapeError
from ...fitting.accumulate import single_threaded_blas
from ...hybrid.inputs import check_hold, stage_inputs

#: relative ridge on the scaled coefficients while supports are compared
RIDGE = 1e-6
#: terms whose scaled size is below this share of the largest are dropped together
NEGLIGIBLE = 1e-3
#: contiguous blocks per record for the standard error of a held-out score
SCORE_BLOCKS = 8
#: contiguous blocks per record for the coefficients' covariance
COVARIANCE_BLOCKS = 20


class _Record:
    """One trajectory: times, outputs ``(m, k)``, stage inputs and step lengths."""

    def __init__(self, trajectory, n_inputs, substeps, hold):
        self.t, self.y, self.u = trajectory.t, trajectory.x, trajectory.u
        self.h = np.diff(self.t)
        self.stages = None if not n_inputs else stage_inputs(self.u, self.t, n_inputs,
                                                              substeps, hold=hold)
        self.m = len(self.t)

    def head(self, samples: int) -> _Record:
        """The first ``samples`` samples of this record (a shallow copy)."""
        out = copy.copy(self)
        out.t, out.y, out.h = self.t[:samples], self.y[:samples], self.h[:samples - 1]
        out.u = None if self.u is None else self.u[:samples]
        out.stages = None if self.stages is None else self.stages[:samples - 1]
        out.m = len(out.t)
        return out


class OutputErrorFit:
    """The pieces of one fit: model discretisation, records, output map and scales."""

    def __init__(self, setup, records, out_map, shooting, allowed):
        self.setup, self.records, self.out_map = setup, records, out_map
        self.shooting, self.allowed = shooting, allowed
        y = np.vstack([r.y for r in records])
        spread = y.std(axis=0)
        self.y_scale = np.where(spread > 0, spread, np.maximum(np.abs(y).max(axis=0), 1.0))
        self.n, self.p = setup.n_states, setup.n_features
        self.coef_scale = np.ones(self.n * self.p)      # set from the data by set_coef_scale
        self.bounds = (np.full(self.n, -np.inf), np.full(self.n, np.inf))   # of x0
        self.fixed = np.zeros((self.n, self.p))   # coefficients outside the fitted support

    def head(self, samples: int) -> OutputErrorFit:
        """This fit on the first ``samples`` samples of every record (same scales, bounds and
        fixed coefficients; the model and its compiled code shared)."""
        out = copy.copy(self)
        out.records = [r.head(samples) for r in self.records]
        return out

    # ---------------------------------------------------------------- residuals
    def _parts(self, theta, support):
        index = np.flatnonzero(support.ravel())
        coef = self.fixed.ravel().copy()
        coef[index] = theta[:len(index)] * self.coef_scale[index]
        x0s = theta[len(index):].reshape(len(self.records), self.n)
        return index, coef, x0s

    def residuals(self, theta, support, rows, ridge, *, jacobian: bool = True):
        """Residual vector (and its Jacobian) for ``theta`` = [scaled coefficients of
        ``support``, x0 of every record]; ``rows[i]``: the samples of record ``i`` fitted.
        Without ``jacobian`` only the simulation runs (trial steps)."""
        index, coef, x0s = self._parts(theta, support)
        total = sum(int(r.sum()) for r in rows) * self.out_map.k
        parts, jacobians = [], []
        width = len(index) + x0s.size
        for i, (record, fit_rows) in enumerate(zip(self.records, rows, strict=True)):
            if not jacobian:
                states = self.shooting.simulate(x0s[i], record.stages, record.h, coef)
                parts.append(((self.out_map(states[fit_rows]) - record.y[fit_rows])
                              / self.y_scale).ravel())
                continue
            sens = self.shooting.sensitivities(x0s[i], record.stages, record.h, coef,
                                               coefficients=len(index) > 0)
            states = sens.states[fit_rows]
            parts.append(((self.out_map(states) - record.y[fit_rows]) / self.y_scale).ravel())
            dh = self.out_map.jacobian(states) / self.y_scale[None, :, None]   # (m, k, n)
            jac = np.zeros((states.shape[0], self.out_map.k, width))
            jac[:, :, :len(index)] = np.einsum("mkn,mnc->mkc", dh,
                                               sens.d_coefficients(index)[fit_rows]) \
                * self.coef_scale[index]
            offset = len(index) + i * self.n
            jac[:, :, offset:offset + self.n] = np.einsum("mkn,mnj->mkj", dh,
                                                          sens.d_x0[fit_rows])
            jacobians.append(jac.reshape(-1, width))
        scale = 1 / np.sqrt(max(total, 1))
        r = np.concatenate(parts) * scale
        if ridge and len(index):
            r = np.concatenate([r, np.sqrt(ridge) * theta[:len(index)]])
        diverged = not np.all(np.isfinite(r))
        if diverged:
            r = np.full_like(r, 1e6)                       # a diverging trial is rejected
        if not jacobian:
            return r
        J = np.vstack(jacobians) * scale
        if ridge and len(index):
            J = np.vstack([J, np.sqrt(ridge) * np.eye(len(index), width)])
        if diverged:
            return r, np.zeros_like(J)                     # nowhere to go from here
        # an infinite slope (sqrt at 0) or an undefined one at a kink counts as flat there
        return r, np.nan_to_num(J, nan=0.0, posinf=0.0, neginf=0.0)

    def solve(self, support, coef, x0s, rows, ridge, *, max_evaluations: int = 200):
        """Least squares from ``coef`` ``(n, p)`` and ``x0s``; returns ``(coef, x0s, cost)``.
        ``max_evaluations`` bounds the simulations (supports on the path that fit badly
        need not converge far to be seen to be bad)."""
        index = np.flatnonzero(support.ravel())
        lower = np.concatenate([np.full(len(index), -np.inf),
                                np.tile(self.bounds[0], len(self.records))])
        upper = np.concatenate([np.full(len(index), np.inf),
                                np.tile(self.bounds[1], len(self.records))])
        theta0 = np.clip(np.concatenate([coef.ravel()[index] / self.coef_scale[index],
                                         x0s.ravel()]), lower, upper)
        with np.errstate(all="ignore"), single_threaded_blas():
            result = self._least_squares(support, rows, ridge, theta0, lower, upper,
                                         max_evaluations)
        _, flat, x0s = self._parts(result.x, support)
        return flat.reshape(self.n, self.p), x0s, float(2 * result.cost)

    def _least_squares(self, support, rows, ridge, theta0, lower, upper, max_evaluations):
        return scipy.optimize.least_squares(
            lambda th: self.residuals(th, support, rows, ridge, jacobian=False), theta0,
            jac=lambda th: self.residuals(th, support, rows, ridge)[1], method="trf",
            bounds=(lower, upper), x_scale="jac", max_nfev=max_evaluations, xtol=1e-9,
            ftol=1e-9, gtol=1e-9)

    def coefficient_covariance(self, support, coef, x0s, rows, blocks: int = COVARIANCE_BLOCKS):
        """Covariance ``(n p, n p)`` of the fitted coefficients (zero off ``support``): the
        Gauss–Newton sandwich ``B⁻¹ M B⁻¹`` with ``B = JᵀJ`` and ``M`` summed over
        ``blocks`` contiguous blocks of samples per record (``Σ_b J_bᵀ r_b r_bᵀ J_b``), so
        errors correlated in time widen it as they should; initial states are profiled.
        ``covariance_blocks`` keeps the number of blocks (the degrees of freedom + 1)."""
        index = np.flatnonzero(support.ravel())
        theta = np.concatenate([coef.ravel()[index] / self.coef_scale[index], x0s.ravel()])
        r, J = self.residuals(theta, support, rows, 0.0)
        k = self.out_map.k
        bread = np.linalg.pinv(J.T @ J)
        meat = np.zeros_like(bread)
        start, count = 0, 0
        for w in rows:
            size = int(w.sum()) * k
            for part in np.array_split(np.arange(start, start + size), min(blocks, size)):
                score = J[part].T @ r[part]
                meat += np.outer(score, score)
                count += 1
            start += size
        self.covariance_blocks = count
        meat *= count / max(count - 1, 1)       # the usual small-sample correction
        scaled = (bread @ meat @ bread)[:len(index), :len(index)]
        out = np.zeros((self.n * self.p, self.n * self.p))
        out[np.ix_(index, index)] = scaled * np.outer(self.coef_scale[index],
                                                      self.coef_scale[index])
        return out

    # ------------------------------------------------------------------ scores
    def simulate_outputs(self, coef, x0s):
        """The outputs of every record simulated with coefficients ``coef`` from the initial states
        ``x0s``, one ``(m, k)`` array per record."""
        return [self.out_map(self.shooting.simulate(x0, r.stages, r.h, coef))
                for x0, r in zip(x0s, self.records, strict=True)]

    def record_errors(self, coef, x0s) -> np.ndarray:
        """RMS output error of each record ``(records, k)`` in the outputs' units."""
        return np.array([np.sqrt(np.mean((sim - r.y) ** 2, axis=0)) for sim, r in
                         zip(self.simulate_outputs(coef, x0s), self.records, strict=True)])

    def error(self, coef, x0s, rows) -> float:
        """RMS of the scaled output error on the given rows of every record."""
        return float(np.sqrt(self.squared_errors(coef, x0s, rows)[0]))

    def squared_errors(self, coef, x0s, rows, blocks: int = SCORE_BLOCKS):
        """Mean squared scaled output error on ``rows`` and its standard error, estimated
        from the means of ``blocks`` contiguous blocks of each record's rows (the errors of a
        simulation are correlated in time, so samples are not independent)."""
        sims = self.simulate_outputs(coef, x0s)
        means = []
        for sim, record, w in zip(sims, self.records, rows, strict=True):
            e2 = np.mean(((sim - record.y) / self.y_scale)[w] ** 2, axis=1)
            if not np.all(np.isfinite(e2)):
                return np.inf, np.inf
            means.extend(block.mean() for block in np.array_split(e2, min(blocks, len(e2))))
        means = np.array(means)
        return float(means.mean()), float(means.std(ddof=1) / np.sqrt(len(means)))

    def set_coef_scale(self, x0s):
        """Scale of each coefficient: its equation's derivative scale over its column's RMS
        along the simulation of the fixed part (the prior, or the model being refitted), so
        that scaled sizes compare across terms. A simulation that diverges counts up to its
        last finite sample (a scale of 1 where nothing is finite). Returns the indices of
        the records whose simulation diverged."""
        theta_rms, dx_rms, diverged = [], [], []
        for i, (x0, r) in enumerate(zip(x0s, self.records, strict=True)):
            states = self.shooting.simulate(x0, r.stages, r.h, self.fixed)
            if not np.isfinite(states).all():
                diverged.append(i)
            theta = self.shooting.theta(states, r.u)
            dx = np.diff(states, axis=0) / r.h[:, None]
            theta_rms.append(_finite_mean_square(theta))
            dx_rms.append(_finite_mean_square(dx))
        theta, dx = _pooled_rms(theta_rms), _pooled_rms(dx_rms)
        dx = np.where(dx > 0, dx, max(float(np.nan_to_num(dx).max()), 1.0))
        theta = np.where(theta > 0, theta, 1.0)
        self.coef_scale = (dx[:, None] / theta[None, :]).ravel()
        return diverged

    def compensated(self, coef, dropped, x0s) -> np.ndarray:
        """A start for the support without the ``dropped`` terms: the remaining terms of each
        equation absorb, by least squares along the current simulated trajectories, what the
        dropped ones contributed, so the model's derivatives (and its simulation) barely
        move; refitting from there does not have to find its way back from a divergence."""
        thetas = [self.shooting.theta(self.shooting.simulate(x0, r.stages, r.h, coef), r.u)
                  for x0, r in zip(x0s, self.records, strict=True)]
        theta = np.vstack(thetas)
        out = np.where(dropped, 0.0, coef)
        for i in np.flatnonzero(dropped.any(axis=1)):
            keep = np.flatnonzero(out[i] != 0)
            lost = theta[:, dropped[i]] @ coef[i, dropped[i]]
            if keep.size and np.all(np.isfinite(theta[:, keep])) and np.all(np.isfinite(lost)):
                out[i, keep] += np.linalg.lstsq(theta[:, keep], lost, rcond=None)[0]
        return out

    def importance(self, coef) -> np.ndarray:
        """Size of each coefficient relative to its scale, ``|ξ| / scale``, flattened (to rank
        terms)."""
        return np.abs(coef.ravel()) / self.coef_scale


#: most RK4 substeps per sample interval output error accepts: every substep is unrolled
#: into the exact derivatives the fit differentiates (10,000 on 3 samples did not finish
#: building in 20 s); finer steps belong in a resampled record
MAX_SUBSTEPS = 100


def _finite_mean_square(values) -> np.ndarray:
    """Mean square of each column of ``values`` over its finite rows (NaN if none)."""
    finite = np.isfinite(values).all(axis=1)
    if not finite.any():
        return np.full(values.shape[1], np.nan)
    return np.mean(values[finite] ** 2, axis=0)


def _pooled_rms(mean_squares) -> np.ndarray:
    """Root of the mean over records of per-record mean squares, records without finite
    samples left out (NaN where no record has any)."""
    stacked = np.asarray(mean_squares)
    counted = np.isfinite(stacked)
    total = np.where(counted, stacked, 0.0).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(np.where(counted.any(axis=0), total / counted.sum(axis=0), np.nan))


def records_of(model, y, t, u, substeps, hold):
    """The records of ``y``, ``t``, ``u`` prepared for simulation, and the number of inputs ``r``.
    ``substeps`` is checked first (an integer in ``[1, MAX_SUBSTEPS]``)."""
    if isinstance(substeps, (bool, np.bool_)) or not isinstance(substeps, (int, np.integer)) \
            or not 1 <= substeps <= MAX_SUBSTEPS:
        raise ParameterError(f"substeps must be an integer in [1, {MAX_SUBSTEPS}] (RK4 steps per "
                             "sample interval; for finer steps resample the record); got "
                             f"{substeps!r}")
    trajectories = as_trajectories(y, t, u, x_name="y")
    r = 0 if trajectories[0].u is None else trajectories[0].u.shape[1]
    return [_Record(tr, r, substeps, check_hold(hold)) for tr in trajectories], r


def n_states_of(model, x0) -> int:
    """Number of states of the model: from ``state_names``, a sympy prior or ``x0``."""
    if model.state_names is not None:
        return 1 if isinstance(model.state_names, str) else len(model.state_names)
    if isinstance(model.prior, (list, tuple)):
        return len(model.prior)
    if x0 is not None:
        return int(np.shape(x0)[-1])
    raise ParameterError("the number of states is unknown: give state_names, a prior as a "
                         "list of sympy expressions, or x0")


def output_size(fit) -> float:
    """The outputs' typical size: their mean absolute value over the records (1 if all 0)."""
    return float(np.mean([np.abs(r.y).mean() for r in fit.records])) or 1.0


def signed_starts(fit, base, states) -> list[np.ndarray]:
    """``base`` ``(records, n)`` with ``states`` at plus and at minus :func:`output_size`
    (a state at 0 can be a fixed point a fit cannot leave)."""
    starts = []
    for sign in (1.0, -1.0):
        x0s = base.copy()
        x0s[:, states] = sign * output_size(fit)
        starts.append(x0s)
    return starts


def initial_states(x0, records, out_map, n) -> np.ndarray:
    """``(records, n)`` initial guesses: given, or measured states from the first sample."""
    if x0 is None:
        return np.array([out_map.initial_guess(r.y[0]) for r in records])
    x0s = np.asarray(x0, dtype=float).reshape(-1, n) if np.size(x0) % n == 0 else None
    if x0s is None or len(x0s) not in (1, len(records)) or not np.all(np.isfinite(x0s)):
        raise ShapeError(f"x0 must be {n} finite numbers (one per state), or one such row per "
                         f"trajectory; got shape {np.shape(x0)}")
    return np.repeat(x0s, len(records), axis=0) if len(x0s) == 1 else x0s


def check_identifiable(fit):
    """Every state must be able to move a measured output, through the prior or an allowed
    term (a chain of dependencies in the model's structure); one that cannot is
    unidentifiable and is refused by name."""
    influences = fit.shooting.influences(fit.allowed)
    reached = set(fit.out_map.measured)
    grew = True
    while grew:
        new = {i for j in reached for i in np.flatnonzero(influences[j])} - reached
        reached |= new
        grew = bool(new)
    dead = [name for i, name in enumerate(fit.setup.state_names) if i not in reached]
    if dead:
        raise DataError(f"state(s) {dead} cannot influence the measured outputs "
                        f"{fit.out_map.names} through the prior or any allowed term, so they "
                        "cannot be estimated (unidentifiable): measure them or a quantity "
                        "they affect, or leave them out of the model")


def warn_if_not_converged(fit, coef, x0s, rows):
    """The fit's output error; warns when the fitted model's simulation diverges on the data."""
    err = fit.error(coef, x0s, rows)
    if not np.isfinite(err):
        warnings.warn("the fitted model's simulation diverges on the data", stacklevel=4)
    return err


def split_rows(records, holdout) -> tuple[list, list]:
    """Training rows (the first part of each record) and held-out rows (the rest)."""
    train, test = [], []
    for r in records:
        cut = int(round(r.m * (1 - holdout)))
        if cut < 2 or r.m - cut < 2:
            raise DataError(f"a record of {r.m} samples is too short to hold out its last "
                            f"{holdout:.0%} for choosing terms; give threshold= a number or "
                            "longer records")
        w = np.zeros(r.m, bool)
        w[:cut] = True
        train.append(w)
        test.append(~w)
    return train, test


def x0_bounds(bounds, n):
    """``(lower (n,), upper (n,))`` from ``None`` or a pair of numbers or sequences."""
    if bounds is None:
        return np.full(n, -np.inf), np.full(n, np.inf)
    try:
        lower, upper = (np.broadcast_to(np.asarray(b, dtype=float), (n,)).copy()
                        for b in bounds)
    except (TypeError, ValueError):
        raise ParameterError(f"x0_bounds must be (lower, upper), each a number or {n} "
                             f"numbers; got {bounds!r:.80}") from None
    if np.any(np.isnan(lower)) or np.any(np.isnan(upper)) or np.any(lower >= upper):
        raise ParameterError(f"x0_bounds must have lower < upper for every state; got "
                             f"{lower} and {upper}")
    return lower, upper
