"""Output-error fits: the discrepancy and the unmeasured states from what is measured.

When only some states (or functions of them) are recorded, the derivative of every state
is not available and the usual regression cannot be formed. Here the hybrid model is
simulated with the measured input (RK4 at the input's stage times, see
:mod:`discrepancy.models.shooting`) and its coefficients and initial states are chosen to
minimise the simulation error of the recorded outputs.

Multiple shooting: every record is cut into segments (:mod:`discrepancy.models.segments`),
each simulated from a state of its own with its exact sensitivities; the fit adds the
condition that each segment ends where the next begins and solves the constrained least
squares by Levenberg–Marquardt on the sparse KKT system
(:mod:`discrepancy.models.gauss_newton`). At the solution the trajectory is continuous, so
the answer is single shooting's (the simulation error from the initial states); on the way
the short segments keep the problem nearly linear, and they run in parallel.

Sparsity: the whole library is fitted first (with a small ridge on coefficients scaled to
their equation), then terms are removed one at a time, the least important first, each
support refitted from the last (coefficients and segment states: warm starts). With
``threshold="auto"`` the supports are fitted on the first part of every record and scored
by how well they forecast the rest (free simulation of the held-out end); the sparsest
support within ``tolerance`` of the best forecast is refitted on all the data. A fixed
threshold instead drops terms whose coefficients stay below it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..resources import check_memory, n_bytes
from . import gauss_newton
from .segments import DEFAULT_LENGTH, layout

#: relative ridge on the scaled coefficients while supports are compared
RIDGE = 1e-6
#: terms whose scaled size is below this share of the largest are dropped together
NEGLIGIBLE = 1e-3
#: contiguous blocks per record for the standard error of a held-out score
SCORE_BLOCKS = 8
#: contiguous blocks per record for the coefficients' covariance
COVARIANCE_BLOCKS = 20
#: bytes of sensitivities held at once while a fit is evaluated
EVALUATION_BYTES = 2**25


@dataclass
class Solution:
    """A fitted support: coefficients ``(n, p)``, initial states ``(records, n)``, the
    cost (sum of squared scaled residuals, the ridge included), the segment states it
    ended at (for warm starts) and whether the solver met its tolerances."""

    coef: np.ndarray
    x0s: np.ndarray
    cost: float
    starts: np.ndarray | None = None
    converged: bool = True


class OutputErrorFit:
    """The pieces of one fit: model discretisation, records, output map and scales.

    ``parameters``: indices (into the flattened ``Ξ``) of the coefficients that may be
    fitted; sensitivities are computed for these."""

    def __init__(self, setup, records, out_map, shooting, allowed, *, segment_length="auto"):
        self.setup, self.records, self.out_map = setup, records, out_map
        self.shooting, self.allowed = shooting, allowed
        self.parameters = np.flatnonzero(allowed.ravel())
        y = np.vstack([r.y for r in records])
        spread = y.std(axis=0)
        self.y_scale = np.where(spread > 0, spread, np.maximum(np.abs(y).max(axis=0), 1.0))
        self.n, self.p = setup.n_states, setup.n_features
        self.segment_length = DEFAULT_LENGTH if segment_length == "auto" else segment_length
        self.coef_scale = np.ones(self.n * self.p)      # set from the data by set_coef_scale
        self.state_scale = np.ones(self.n)              # likewise
        self.bounds = (np.full(self.n, -np.inf), np.full(self.n, np.inf))   # of x0
        self.fixed = np.zeros((self.n, self.p))   # coefficients outside the fitted support
        self.evaluations = 0
        self._layouts = {}

    # ---------------------------------------------------------------- the solve
    def layout(self, rows):
        """The :class:`~discrepancy.models.segments.SegmentLayout` of shooting segments over
        ``rows`` (per record, the samples whose residuals count), built once per ``rows``."""
        key = tuple(w.tobytes() for w in rows)
        if key not in self._layouts:
            self._layouts[key] = layout(self.records, rows, self.segment_length,
                                        self.shooting)
        return self._layouts[key]

    def coefficients(self, theta, index) -> np.ndarray:
        """``(n, p)``: the fixed part with the scaled ``theta`` of ``index`` put in."""
        coef = self.fixed.ravel().copy()
        coef[index] = theta * self.coef_scale[index]
        return coef.reshape(self.n, self.p)

    def solve(self, support, coef, x0s, rows, ridge, *, max_evaluations: int = 200,
              starts=None) -> Solution:
        """Least squares of ``support`` from ``coef`` ``(n, p)`` and ``x0s``, or from the
        segment ``starts`` of an earlier solution on the same ``rows`` (``"measured"``:
        segments start from the measured states, see :meth:`segment_starts`)."""
        index = np.flatnonzero(support.ravel())
        lay = self.layout(rows)
        params = self.parameters if len(index) else self.parameters[:0]
        if isinstance(starts, str) or starts is None or len(starts) != lay.count:
            starts = self.segment_starts(lay, coef, x0s, measured=isinstance(starts, str))
        first = lay.first_segments()
        starts = starts.copy()
        starts[first] = np.clip(x0s, *self.bounds)
        lower, upper = np.full_like(starts, -np.inf), np.full_like(starts, np.inf)
        lower[first], upper[first] = self.bounds
        sup = np.searchsorted(params, index)
        with np.errstate(all="ignore"):
            result = gauss_newton.solve(
                lambda s, th: self.evaluate(lay, index, params, sup, s, th, ridge), starts,
                coef.ravel()[index] / self.coef_scale[index], lay.links,
                state_scale=self.state_scale, lower=lower, upper=upper,
                continuous=lambda s, th: self.continuous(lay, index, s, th, ridge),
                max_evaluations=max_evaluations)
        self.evaluations += result.evaluations
        coef = self.coefficients(result.theta, index)
        return Solution(coef, result.states[first].copy(), result.cost, result.states,
                        result.converged)

    def segment_starts(self, lay, coef, x0s, *, measured: bool = False) -> np.ndarray:
        """Segment states from simulating each record from its initial state; where the
        simulation diverged, the measured states of the sample (the others 0). With
        ``measured``, every segment after a record's first starts from the measured
        states of its sample (the unmeasured ones from the simulation): the classic start
        of multiple shooting, close to the data wherever the model is still wrong."""
        starts = np.empty((lay.count, self.n))
        for i, record in enumerate(self.records):
            mine = lay.starts_of(i)
            end = int(lay.first[mine[-1]] + lay.steps[mine[-1]])
            stages = record.stages[:end] if record.stages is not None else None
            states = self.shooting.simulate(x0s[i], stages, record.h[:end], coef)
            chosen = states[lay.first[mine]]
            bad = ~np.all(np.isfinite(chosen), axis=1)
            for j in np.flatnonzero(bad):
                chosen[j] = self.out_map.initial_guess(record.y[lay.first[mine[j]]])
            for j in range(1, len(mine)) if measured else ():
                chosen[j] = self.out_map.states_from(record.y[lay.first[mine[j]]], chosen[j])
            starts[mine] = chosen
        return starts

    def continuous(self, lay, index, starts, theta, ridge):
        """``(segment starts, cost)`` of the continuous trajectory of every record from
        its first segment's state (a plain simulation), for :func:`gauss_newton.solve`."""
        coef = self.coefficients(theta, index)
        out, cost = starts.copy(), 0.0
        total = max(float(lay.weight.sum()) * self.out_map.k, 1.0)
        for i, record in enumerate(self.records):
            mine = lay.starts_of(i)
            end = int(lay.first[mine[-1]] + lay.steps[mine[-1]])
            stages = record.stages[:end] if record.stages is not None else None
            states = self.shooting.simulate(starts[mine[0]], stages, record.h[:end], coef)
            w = np.zeros(end + 1)
            for j in mine:
                span = slice(lay.first[j], lay.first[j] + lay.length + 1)
                w[span] = np.maximum(w[span], lay.weight[j, :len(w[span])])
            e = (self.out_map(states) - record.y[:end + 1]) / self.y_scale
            cost += float(np.sum(w[:, None] * e ** 2)) / total
            out[mine] = states[lay.first[mine]]
        if ridge and len(index):
            cost += ridge * float(theta @ theta)
        return out, (cost if np.isfinite(cost) else np.inf)

    def evaluate(self, lay, index, params, sup, starts, theta, ridge):
        """:class:`~discrepancy.models.gauss_newton.Evaluation` at segment ``starts`` and
        scaled coefficients ``theta`` of ``index``: cost, normal-equation blocks and segment
        ends, with sensitivities to ``params`` (``sup``: where ``index`` is in them). The
        Jacobian is formed a batch of segments at a time, never whole."""
        coef = self.coefficients(theta, index)
        N, L, n, q, k = lay.count, lay.length, self.n, len(index), self.out_map.k
        total = max(float(lay.weight.sum()) * k, 1.0)
        weight = lay.weight / np.sqrt(total)
        ev = gauss_newton.Evaluation(0.0, np.zeros((N, n, n)), np.zeros((N, n, q)),
                                     np.zeros((q, q)), np.zeros((N, n)), np.zeros(q),
                                     np.zeros((N, n)), np.zeros((N, n, n)),
                                     np.zeros((N, n, q)))
        scale = self.coef_scale[index]
        width = self.shooting.width(params)
        batch = max(1, EVALUATION_BYTES // (8 * (L + 1) * (width + k * (n + q))))
        for part in lay.batches(batch):
            span = slice(part.start * L, part.stop * L)
            sens = self.shooting.segments(starts[part], lay.cols[span], lay.lengths[span],
                                          coef, params)
            flat = sens.states.reshape(-1, n)
            w = weight[part][..., None]
            e = (self.out_map(flat).reshape(-1, L + 1, k) - lay.y[part]) / self.y_scale * w
            if not np.all(np.isfinite(e)):
                return gauss_newton.Evaluation(np.inf)
            dh = self.out_map.jacobian(flat).reshape(-1, L + 1, k, n) * \
                (w / self.y_scale)[..., None]
            j_s = _flat_where_undefined(np.einsum("btkn,btnj->btkj", dh, sens.d_x0))
            j_p = _flat_where_undefined(np.einsum("btkn,btnq->btkq", dh,
                                                  sens.d_coef[..., sup]) * scale)
            ev.cost += float(np.sum(e ** 2))
            ev.h_ss[part] = np.einsum("btki,btkj->bij", j_s, j_s)
            ev.h_sp[part] = np.einsum("btki,btkq->biq", j_s, j_p)
            ev.h_pp += np.einsum("btkq,btkr->qr", j_p, j_p)
            ev.g_s[part] = np.einsum("btki,btk->bi", j_s, e)
            ev.g_p += np.einsum("btkq,btk->q", j_p, e)
            at = np.arange(part.stop - part.start), lay.steps[part]
            ev.ends[part] = sens.states[at]
            ev.a[part] = _flat_where_undefined(sens.d_x0[at])
            ev.b[part] = _flat_where_undefined(sens.d_coef[at][..., sup] * scale)
        if not np.all(np.isfinite(ev.ends)):
            return gauss_newton.Evaluation(np.inf)
        if ridge and q:
            ev.cost += ridge * float(theta @ theta)
            ev.h_pp += ridge * np.eye(q)
            ev.g_p += ridge * theta
        return ev

    def coefficient_covariance(self, support, coef, x0s, rows, blocks: int = COVARIANCE_BLOCKS):
        """Covariance ``(n p, n p)`` of the fitted coefficients (zero off ``support``): the
        Gauss–Newton sandwich ``B⁻¹ M B⁻¹`` with ``B = JᵀJ`` and ``M`` summed over
        ``blocks`` contiguous blocks of samples per record (``Σ_b J_bᵀ r_b r_bᵀ J_b``), so
        errors correlated in time widen it as they should; initial states are profiled.
        ``covariance_blocks`` keeps the number of blocks (the degrees of freedom + 1)."""
        index = np.flatnonzero(support.ravel())
        q, n, k = len(index), self.n, self.out_map.k
        width = q + n * len(self.records)
        check_memory("the output-error Jacobian", n_bytes((sum(r.m for r in self.records),
                                                           k, n + q)), "Fit fewer samples")
        bread_inv = np.zeros((width, width))
        scores = []
        for i, (record, w) in enumerate(zip(self.records, rows, strict=True)):
            sens = self.shooting.sensitivities(x0s[i], record.stages, record.h, coef, index)
            dh = self.out_map.jacobian(sens.states) / self.y_scale[None, :, None]
            jac = np.zeros((record.m, k, width))
            jac[:, :, :q] = np.einsum("mkn,mnc->mkc", dh, sens.d_coef) * self.coef_scale[index]
            jac[:, :, q + i * n:q + (i + 1) * n] = np.einsum("mkn,mnj->mkj", dh, sens.d_x0)
            r = (self.out_map(sens.states) - record.y) / self.y_scale
            jac = _flat_where_undefined(jac[w].reshape(-1, width))
            r = r[w].ravel()
            bread_inv += jac.T @ jac
            for part in np.array_split(np.arange(len(r)), min(blocks, len(r))):
                scores.append(jac[part].T @ r[part])
        self.covariance_blocks = count = len(scores)
        bread = np.linalg.pinv(bread_inv)
        meat = sum(np.outer(s, s) for s in scores) * count / max(count - 1, 1)
        scaled = (bread @ meat @ bread)[:q, :q]
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

    def error(self, coef, x0s, rows) -> float:
        """RMS of the scaled output error on the given rows of every record."""
        return float(np.sqrt(self.squared_errors(coef, x0s, rows)[0]))

    def record_errors(self, coef, x0s) -> np.ndarray:
        """RMS output error of each record ``(records, k)`` in the outputs' units."""
        return np.array([np.sqrt(np.mean((sim - r.y) ** 2, axis=0)) for sim, r in
                         zip(self.simulate_outputs(coef, x0s), self.records, strict=True)])

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
        that scaled sizes compare across terms; and each state's typical size."""
        theta_rms, dx_rms, x_rms = [], [], []
        for x0, r in zip(x0s, self.records, strict=True):
            states = self.shooting.simulate(x0, r.stages, r.h, self.fixed)
            theta_rms.append(np.mean(self.shooting.theta(states, r.u) ** 2, axis=0))
            dx_rms.append(np.mean((np.diff(states, axis=0) / r.h[:, None]) ** 2, axis=0))
            x_rms.append(np.mean(states ** 2, axis=0))
        theta = np.sqrt(np.mean(theta_rms, axis=0))
        dx = np.sqrt(np.mean(dx_rms, axis=0))
        dx = np.where(dx > 0, dx, max(float(dx.max()), 1.0))
        theta = np.where(theta > 0, theta, 1.0)
        self.coef_scale = (dx[:, None] / theta[None, :]).ravel()
        x = np.sqrt(np.mean(x_rms, axis=0))
        self.state_scale = np.where(np.isfinite(x) & (x > 0), x, 1.0)

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


def _flat_where_undefined(jacobian):
    """An infinite slope (``sqrt`` at 0) or an undefined one at a kink counts as flat."""
    return np.nan_to_num(jacobian, nan=0.0, posinf=0.0, neginf=0.0)
