"""Levenberg–Marquardt for multiple shooting: least squares with continuity constraints.

The problem: ``min ½ ||r(s, θ)||²`` over segment states ``s_1 .. s_N`` (``n`` each) and
shared parameters ``θ`` (``q``), subject to ``F_i(s_i, θ) = s_{i+1}`` for every linked
segment ``i`` (the end of a segment meets the start of the next) and box bounds on some
states. Residuals of segment ``i`` depend on ``s_i`` and ``θ`` only, so ``JᵀJ`` is block
diagonal in the states with a border for ``θ``, and the constraints are banded: each step
solves the sparse KKT system of the linearised, damped problem

    [JᵀJ + μD   Gᵀ] [Δ]   [-Jᵀr]
    [G          0 ] [λ] = [-d  ]         (d: the defects F_i - s_{i+1}, G: their Jacobian)

with SuperLU (scipy) in ``O(N (n + q)²)`` memory, never a dense ``N n × N n`` matrix. A step
is accepted when it lowers the exact ℓ1 penalty ``½||r||² + ρ Σ|d|`` (``ρ`` above the
multipliers) by a share of what its model promised, and the damping ``μ`` follows the
cost's actual over predicted decrease (divided by 5 above 0.75, doubled below
0.25; Nielsen's smooth rule barely lowered it at ratios of 0.6-0.9 and left the steps
crawling along flat valleys of correlated terms) with ``D`` = the diagonal of ``JᵀJ``
(invariant to the variables' scales, like MINPACK). At a solution the defects
vanish, so the answer is a stationary point of single shooting's objective; the segments
only change the path there (and, being short, keep the linearisation good far from it).

Problems provide ``evaluate(states (N, n), theta (q,)) -> Evaluation`` (a
:class:`Evaluation`); :func:`solve` needs nothing else. Written here because scipy's
``least_squares`` has no equality constraints and its dense ``trf`` would factor the whole
``N n + q`` Jacobian; CasADi's NLP solvers would need the record's whole graph.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

#: a step that would cross a bound goes this share of the way to it
INTERIOR = 0.995
#: largest scaled defect below which trials are made continuous (see :func:`solve`)
FEASIBLE = 1e-6
#: continuous trials rejected in a row after which a solve stops making them
CONTINUOUS_FAILURES = 4
#: KKT systems up to this size are solved dense (LAPACK), larger ones by SuperLU
DENSE_SIZE = 300
#: damping of the Gauss–Newton step that tests for a stationary point (keeps the system
#: regular where some state does not move the outputs, e.g. beyond a kink)
STATIONARY_DAMPING = 1e-9


@dataclass
class Evaluation:
    """Everything one step needs at a point, for ``N`` segments, ``n`` states, ``q``
    parameters (``cost = ||r||²``; ``inf`` when the model diverged).

    ``h_ss`` ``(N, n, n)``, ``h_sp`` ``(N, n, q)``, ``h_pp`` ``(q, q)``: blocks of ``JᵀJ``;
    ``g_s`` ``(N, n)``, ``g_p`` ``(q,)``: of ``Jᵀr``; ``ends`` ``(N, n)``: ``F_i`` (rows of
    unlinked segments unused), ``a`` ``(N, n, n)``, ``b`` ``(N, n, q)``: their Jacobians."""

    cost: float
    h_ss: np.ndarray | None = None
    h_sp: np.ndarray | None = None
    h_pp: np.ndarray | None = None
    g_s: np.ndarray | None = None
    g_p: np.ndarray | None = None
    ends: np.ndarray | None = None
    a: np.ndarray | None = None
    b: np.ndarray | None = None


@dataclass
class Result:
    """The solution: ``states`` ``(N, n)``, ``theta`` ``(q,)``, ``cost`` ``||r||²``, the
    largest scaled defect, the evaluations used and whether the tolerances were met."""

    states: np.ndarray
    theta: np.ndarray
    cost: float
    defect: float
    evaluations: int
    converged: bool


def solve(evaluate, states, theta, links, *, state_scale, lower=None, upper=None,
          continuous=None, max_evaluations: int = 200, ftol: float = 1e-10,
          xtol_f: float = 1e-10, xtol: float = 1e-10, dtol: float = 1e-9) -> Result:
    """Minimise from ``states`` ``(N, n)`` and ``theta`` ``(q,)``.

    Args:
        evaluate: ``(states, theta) -> Evaluation``.
        continuous: optional ``(states, theta) -> (states, cost)``: the segment starts of
            the continuous trajectory from the first segments' states (a plain simulation)
            and its cost. Once the defects are below :data:`FEASIBLE`, trial points are
            made continuous this way and judged by their cost alone: close to a solution
            the new, second-order defects of a full step are of the size of its decrease,
            so a penalty on them rejects good steps (the Maratos effect) and along a flat
            valley of correlated terms the iteration crawled.
        links: ``(N,)`` bool, segment ``i``'s end must equal segment ``i + 1``'s start.
        state_scale: ``(n,)`` typical size of each state (for the defects' tolerance).
        lower, upper: ``(N, n)`` bounds on the states (``±inf`` where free).
        max_evaluations: evaluations allowed (each runs the model with sensitivities).
        ftol, dtol: converged when the undamped Gauss–Newton step predicts a relative
            decrease of the cost below ``ftol`` and every scaled defect is below ``dtol``;
        xtol_f, xtol: or (as scipy's ``least_squares`` does, for models whose Gauss–Newton
            model stays poor, e.g. at a kink) when an accepted step that did at least a
            quarter of what it predicted lowered the cost by less than ``xtol_f``
            (relative), or moved the variables by less than ``xtol`` (relative).
    """
    with _one_blas_thread():
        return _solve(evaluate, states, theta, links, state_scale, lower, upper, continuous,
                      max_evaluations, ftol, xtol_f, xtol, dtol)


def _one_blas_thread():
    """BLAS limited to one thread: the systems here are small, and threaded OpenBLAS took
    0.4 s instead of a millisecond for a 180 x 180 solve while other jobs loaded the
    machine (its threads spin waiting for each other)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        from threadpoolctl import ThreadpoolController
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1, user_api="blas")


_CONTROLLER = None


def _solve(evaluate, states, theta, links, state_scale, lower, upper, continuous,
           max_evaluations, ftol, xtol_f, xtol, dtol) -> Result:
    search = _Search(evaluate, np.array(states, dtype=float), np.array(theta, dtype=float),
                     links, state_scale, lower, upper)
    search.continuous = continuous
    converged = False
    while np.isfinite(search.here.cost) and search.used < max_evaluations:
        system = search.system()
        if search.infeasibility.largest(search.here, search.states) <= dtol and \
                abs(search.predicted(system, STATIONARY_DAMPING, approach=1.0)[0]) <= \
                ftol * 0.5 * search.here.cost:
            converged = True
            break
        if not search.try_step(system):
            break
        if search.settled(ftol=xtol_f, xtol=xtol) and \
                search.infeasibility.largest(search.here, search.states) <= dtol:
            converged = True
            break
    here = search.here
    defect = search.infeasibility.largest(here, search.states) if np.isfinite(here.cost) \
        else np.inf
    return Result(search.states, search.theta, float(here.cost), defect, search.used,
                  converged)


class _Search:
    """The iterate, its evaluation and the damping of a Levenberg–Marquardt search."""

    def __init__(self, evaluate, states, theta, links, state_scale, lower, upper):
        self.evaluate, self.links = evaluate, links
        self.lower = np.full_like(states, -np.inf) if lower is None else lower
        self.upper = np.full_like(states, np.inf) if upper is None else upper
        self.lo = np.concatenate([self.lower.ravel(), np.full(theta.size, -np.inf)])
        self.hi = np.concatenate([self.upper.ravel(), np.full(theta.size, np.inf)])
        self.states = strictly_inside(states, self.lower, self.upper)
        self.theta = theta
        self.here = evaluate(self.states, theta)
        self.used, self.mu, self.nu = 1, 1e-3, 2.0
        self.last = None            # (relative decrease, ratio, relative step) of the last
        self.infeasibility = _Infeasibility(links, state_scale)
        self.rho, self.continuous, self.failures = 0.0, None, 0

    def system(self):
        h, g, G = _assemble(self.here, self.links)
        d = _defects(self.here, self.states, self.links)[np.flatnonzero(self.links[:-1])]
        return h, g, G, d.ravel(), np.concatenate([self.states.ravel(), self.theta])

    def predicted(self, system, mu, approach=None):
        """``(predicted decrease of the cost, step, multipliers)`` of the step damped by
        ``mu`` (with ``approach=1``, variables that would cross a bound stop on it: the
        decrease left inside the bounds)."""
        h, g, G, d, x = system
        step, multipliers = _kkt_step(h, g, G, d, mu, x, self.lo, self.hi,
                                      INTERIOR if approach is None else approach)
        if step is None:
            return np.inf, None, None
        return -(g @ step + 0.5 * step @ (h @ step)), step, multipliers

    def try_step(self, system) -> bool:
        """One damped step, accepted or not; False when no step can be made."""
        predicted, step, multipliers = self.predicted(system, self.mu)
        if step is None:
            return False
        n_seg, n = self.states.shape
        states = strictly_inside(self.states + step[:n_seg * n].reshape(n_seg, n),
                                 self.lower, self.upper)
        theta = self.theta + step[n_seg * n:]
        if self.continuous is not None and \
                self.infeasibility.largest(self.here, self.states) <= FEASIBLE:
            return self._continuous_step(states, theta, predicted, system[4])
        trial = self.evaluate(states, theta)
        self.used += 1
        f, f_trial = 0.5 * self.here.cost, 0.5 * trial.cost
        d = np.abs(system[3]).sum()
        d_trial = np.abs(_defects(trial, states, self.links)).sum()
        if d > 0:                       # the exact penalty's weight: above the multipliers
            self.rho = max(self.rho, 1.1 * np.abs(multipliers).max(initial=0.0),
                           -2.2 * predicted / d)
        merit_decrease = f - f_trial + self.rho * (d - d_trial)
        promised = predicted + self.rho * d
        if not (np.isfinite(f_trial) and np.isfinite(d_trial) and promised > 0
                and merit_decrease >= 1e-4 * promised):
            return self._reject()
        # the damping follows the cost's own agreement with its model: the new defects of
        # a full step near a solution are of the size of its decrease (the Maratos effect)
        # and would keep the merit's ratio, and the damping, high
        ratio = (f - f_trial) / predicted if predicted > 0 else merit_decrease / promised
        self._accept(states, theta, trial, f - f_trial, ratio, system[4])
        return True

    def _reject(self) -> bool:
        self.mu, self.nu = self.mu * self.nu, self.nu * 2.0
        self.last = None
        return self.mu < 1e16

    def _accept(self, states, theta, trial, decrease, ratio, x_before):
        self.mu *= 0.2 if ratio > 0.75 else 2.0 if ratio < 0.25 else 1.0
        self.nu = 2.0
        size = np.abs(np.concatenate([states.ravel(), theta]) - x_before).max(initial=0.0)
        self.last = (decrease / max(0.5 * self.here.cost, 1e-300), ratio,
                     size / max(np.abs(x_before).max(initial=0.0), 1e-300))
        self.states, self.theta, self.here = states, theta, trial

    def _continuous_step(self, states, theta, predicted, x_before) -> bool:
        """A trial made continuous (see :func:`solve`), accepted on an Armijo decrease of
        the cost; after :data:`CONTINUOUS_FAILURES` rejections in a row (a trajectory that
        cannot be run from the first state, e.g. an unstable one) the segments' own states
        are used again."""
        starts, cost = self.continuous(states, theta)
        self.used += 1
        f, f_trial = 0.5 * self.here.cost, 0.5 * cost
        if not (np.isfinite(f_trial) and predicted > 0 and f - f_trial >= 1e-4 * predicted):
            self.failures += 1
            if self.failures >= CONTINUOUS_FAILURES:
                self.continuous = None
            return self._reject()
        self.failures = 0
        trial = self.evaluate(starts, theta)
        if not np.isfinite(trial.cost):
            self.continuous = None
            return self._reject()
        self._accept(starts, theta, trial, f - 0.5 * trial.cost,
                     (f - 0.5 * trial.cost) / predicted, x_before)
        return True

    def settled(self, *, ftol, xtol) -> bool:
        """The last step was accepted and changed little (see :func:`solve`)."""
        if self.last is None:
            return False
        decrease, ratio, size = self.last
        return (decrease < ftol and ratio > 0.25) or size < xtol


def strictly_inside(x, lower, upper, margin: float = 1e-10):
    """``x`` moved inside ``[lower, upper]`` by ``margin`` of the bound's size where it is on
    or beyond a (finite) bound."""
    with np.errstate(invalid="ignore"):
        low = np.where(np.isfinite(lower), lower + margin * np.maximum(1.0, np.abs(lower)),
                       lower)
        high = np.where(np.isfinite(upper), upper - margin * np.maximum(1.0, np.abs(upper)),
                        upper)
    return np.clip(x, np.minimum(low, high), np.maximum(low, high))


class _Infeasibility:
    """Sum (and largest) of the defects scaled by the states' sizes."""

    def __init__(self, links, state_scale):
        self.links, self.scale = links, state_scale

    def __call__(self, ev, states) -> float:
        return float(np.sum(np.abs(_defects(ev, states, self.links)) / self.scale))

    def largest(self, ev, states) -> float:
        return float(np.max(np.abs(_defects(ev, states, self.links)) / self.scale,
                            initial=0.0))


def _defects(ev: Evaluation, states, links) -> np.ndarray:
    """``(N, n)``: ``F_i - s_{i+1}`` where linked, else 0."""
    if ev.ends is None:
        return np.full_like(states, np.inf)
    out = np.zeros_like(states)
    out[:-1] = np.where(links[:-1, None], ev.ends[:-1] - states[1:], 0.0)
    return out


def _assemble(ev: Evaluation, links):
    """``JᵀJ`` (sparse), ``Jᵀr`` and the constraint Jacobian ``G`` (rows of linked
    segments, ``n`` each)."""
    n_seg, n = ev.g_s.shape
    q = ev.g_p.size
    size = n_seg * n + q
    base = np.arange(n_seg)[:, None, None] * n
    ii = np.arange(n)
    rows = [(base + ii[:, None]).repeat(n, 2).ravel()]
    cols = [(base + ii[None, :]).repeat(n, 1).ravel()]
    vals = [ev.h_ss.ravel()]
    if q:
        r_sp = (base + ii[:, None]).repeat(q, 2)
        c_sp = np.broadcast_to(n_seg * n + np.arange(q), r_sp.shape)
        rows += [r_sp.ravel(), c_sp.ravel()]
        cols += [c_sp.ravel(), r_sp.ravel()]
        vals += [ev.h_sp.ravel(), ev.h_sp.ravel()]
        pp = n_seg * n + np.arange(q)
        rows.append(np.repeat(pp, q))
        cols.append(np.tile(pp, q))
        vals.append(ev.h_pp.ravel())
    h = scipy.sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                         np.concatenate(cols))),
                                shape=(size, size))
    g = np.concatenate([ev.g_s.ravel(), ev.g_p])
    linked = np.flatnonzero(links[:-1])
    m = len(linked)
    row = np.arange(m)[:, None, None] * n + ii[None, :, None]            # (m, n, 1)
    parts_r = [np.broadcast_to(row, (m, n, n)).ravel(), (np.arange(m)[:, None] * n + ii).ravel()]
    parts_c = [np.broadcast_to(linked[:, None, None] * n + ii[None, None, :], (m, n, n)).ravel(),
               ((linked + 1)[:, None] * n + ii).ravel()]
    parts_v = [ev.a[linked].ravel(), -np.ones(m * n)]
    if q:
        parts_r.append(np.broadcast_to(row, (m, n, q)).ravel())
        parts_c.append(np.broadcast_to(n_seg * n + np.arange(q), (m, n, q)).ravel())
        parts_v.append(ev.b[linked].ravel())
    G = scipy.sparse.csr_matrix((np.concatenate(parts_v), (np.concatenate(parts_r),
                                                            np.concatenate(parts_c))),
                                shape=(m * n, size))
    return h, g, G


def _kkt_step(h, g, G, d_linked, mu, x, lo, hi, approach=None):
    """The damped step ``Δ`` from ``x`` and the constraints' multipliers (``None, None``
    when the system is singular); bounds
    met by pinning each variable a step would push across its bound at ``approach``
    (default :data:`INTERIOR`) of the way there, and solving again (iterates stay strictly
    inside, as in scipy's ``trf``: a model can have an infinite slope on a bound, such as
    ``sqrt`` at 0)."""
    size = h.shape[0]
    diag = h.diagonal()
    floor = 1e-12 * max(float(diag.max(initial=0.0)), 1e-300)
    damped = h + scipy.sparse.diags(mu * np.maximum(diag, floor))
    target = np.full(size, np.nan)                 # pinned steps (to the bound)
    for _ in range(int(np.isfinite(lo).sum() + np.isfinite(hi).sum()) + 1):
        index = np.flatnonzero(np.isfinite(target))
        P = scipy.sparse.csr_matrix((np.ones(len(index)), (np.arange(len(index)), index)),
                                    shape=(len(index), size))
        K = scipy.sparse.bmat([[damped, G.T, P.T], [G, None, None], [P, None, None]],
                              format="csc")
        rhs = np.concatenate([-g, -d_linked, target[index]])
        try:
            sol = np.linalg.solve(K.toarray(), rhs) if K.shape[0] <= DENSE_SIZE else \
                scipy.sparse.linalg.splu(K).solve(rhs)
        except (RuntimeError, np.linalg.LinAlgError):      # singular: no step from here
            return None, None
        if not np.all(np.isfinite(sol)):
            return None, None
        step = sol[:size]
        above, below = x + step > hi, x + step < lo
        crossing = np.isnan(target) & (above | below)
        if not crossing.any():
            return step, sol[size:size + G.shape[0]]
        share = INTERIOR if approach is None else approach
        target[crossing] = share * (np.where(above, hi, lo)[crossing] - x[crossing])
    return None, None
