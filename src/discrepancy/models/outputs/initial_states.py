"""Initial states from several starts, the best chosen by its fit to the outputs.

A least-squares fit of the initial state is local: from a poor start (an unmeasured state
at 0, which can be a fixed point; the wrong branch of a rectified or squared output) it
stops at a state that fits the window badly, and a simulation from there carries that
error through the whole record. So every fit of initial states starts from several
candidates and keeps, per record, the one whose fitted state reproduces the outputs best:

* ``given``: the caller's ``x0``;
* ``measured``: measured states at their first sample, the others 0;
* ``signs``: the unmeasured states at plus and minus the outputs' typical size;
* ``inverse``: for outputs that are expressions of the states, solutions of
  ``h(x) = y[0]`` for the states they measure, from starts of both signs;
* ``steady state``: the model's equilibrium with the first input (Newton's method), whole
  and with the measured states taken from the data.

When even the best fits the outputs with an RMS error above :data:`POOR_FIT` of their
spread, :class:`~discrepancy.errors.InitialStateWarning` says so.
"""
from __future__ import annotations

import itertools
import warnings

import numpy as np

from ...errors import InitialStateWarning
from .output_error import initial_states, output_size, signed_starts

#: RMS error of the best start, relative to the outputs' spread, above which it warns
POOR_FIT = 0.25
#: evaluations each start gets before the best is refined (most converge in under ten)
SCREENING_EVALUATIONS = 30
#: Newton iterations for steady states and output inverses
NEWTON_ITERATIONS = 50


def candidates(fit, coef, *, given=None) -> list[tuple[str, np.ndarray]]:
    """``[(label, x0s (records, n)), ...]`` to start the fit of initial states from."""
    guess = initial_states(None, fit.records, fit.out_map, fit.n)
    base = guess if given is None else given
    out = [] if given is None else [("given", given)]
    out.append(("measured", guess))
    for x0s in _inverse(fit, guess):
        out.append(("inverse", x0s))
    hidden = sorted(set(range(fit.n)) - fit.out_map.measured)
    if hidden:
        out += [("signs", x0s) for x0s in signed_starts(fit, base, hidden)]
    steady = _steady_states(fit, coef, base)
    if steady is not None:
        out.append(("steady state", steady))
        if hidden:
            mixed = base.copy()
            mixed[:, hidden] = steady[:, hidden]
            out.append(("steady state (unmeasured states)", mixed))
    unique = []
    for label, x0s in out:
        x0s = np.clip(x0s, *fit.bounds)
        if np.all(np.isfinite(x0s)) and not any(np.allclose(x0s, u) for _, u in unique):
            unique.append((label, x0s))
    return unique


def best_start(fit, coef, rows, starts):
    """Fit the initial states (``coef`` held, ``fit.fixed`` set to it) from every start,
    each for at most :data:`SCREENING_EVALUATIONS`; per record, the fitted state with the
    smallest output error, refined to convergence. Returns ``(x0s, labels, rms (records,
    k))``."""
    none = np.zeros((fit.n, fit.p), bool)
    fit.fixed = coef
    best_x0, labels, best_rms = None, None, None
    for label, start in starts:
        _, screened, _ = fit.solve(none, coef, start, rows, 0.0,
                                   max_evaluations=SCREENING_EVALUATIONS)
        rms = fit.record_errors(coef, screened)
        if best_x0 is None:
            best_x0, labels, best_rms = screened.copy(), [label] * len(rms), rms
            continue
        better = _score(fit, rms) < _score(fit, best_rms)
        best_x0[better], best_rms[better] = screened[better], rms[better]
        labels = [label if b else old for b, old in zip(better, labels, strict=True)]
    _, solution, _ = fit.solve(none, coef, best_x0, rows, 0.0)
    rms = fit.record_errors(coef, solution)
    better = _score(fit, rms) <= _score(fit, best_rms)
    best_x0[better], best_rms[better] = solution[better], rms[better]
    return best_x0, labels, best_rms


def _score(fit, rms) -> np.ndarray:
    """Mean squared scaled output error of each record ``(records,)`` from its RMS errors
    ``(records, k)`` (inf if diverged)."""
    score = np.mean((rms / fit.y_scale) ** 2, axis=1)
    return np.where(np.isfinite(score), score, np.inf)


def warn_if_poor(rms, labels, spread, n_starts: int):
    """:class:`InitialStateWarning` when a record's best start fits its outputs with an
    RMS error above :data:`POOR_FIT` of ``spread`` ``(k,)``."""
    relative = rms / spread
    for i, row in enumerate(relative):
        if np.all(row <= POOR_FIT):
            continue
        worst = int(np.argmax(np.where(np.isfinite(row), row, np.inf)))
        warnings.warn(
            f"the best of {n_starts} initial states ({labels[i]!r}) fits record {i}'s "
            f"outputs poorly: RMS error {rms[i, worst]:.3g}, {row[worst]:.2f} times the "
            f"outputs' spread {spread[worst]:.3g} (output {worst}); the model may not "
            "reach the measured state from any start tried: give x0= or a longer window",
            InitialStateWarning, stacklevel=4)


def _inverse(fit, guess) -> list[np.ndarray]:
    """Solutions of ``h(x) = y[0]`` for the measured states, from starts of both signs
    (none when every output is a state: then ``measured`` is the inverse)."""
    if fit.out_map.selected is not None:
        return []
    measured = sorted(fit.out_map.measured)
    if not measured or len(measured) > 3:
        return []
    size = output_size(fit)
    found = []
    for signs in itertools.product((1.0, -1.0), repeat=len(measured)):
        x0s = guess.copy()
        x0s[:, measured] = np.array(signs) * size
        for i, record in enumerate(fit.records):
            x0s[i] = _newton(lambda x, y0=record.y[0]: fit.out_map(x[None])[0] - y0,
                             lambda x: fit.out_map.jacobian(x[None])[0], x0s[i], measured)
        found.append(x0s)
    return found


def _steady_states(fit, coef, base):
    """The model's equilibrium with each record's first input ``(records, n)``, or None
    where Newton's method does not find one."""
    out = base.copy()
    for i, record in enumerate(fit.records):
        u0 = np.zeros(0) if record.u is None else record.u[0]
        f, jac = fit.shooting.rhs_and_jacobian(u0, coef)
        x = _newton(f, jac, base[i], list(range(fit.n)))
        if not np.all(np.isfinite(x)) or np.linalg.norm(f(x)) > 1e-8 * max(
                1.0, float(np.linalg.norm(f(base[i])))):
            return None
        out[i] = x
    return out


def _newton(f, jac, x, free) -> np.ndarray:
    """Least-squares Newton (Gauss–Newton with halving) on ``f(x) = 0`` over ``x[free]``."""
    x = np.array(x, dtype=float)
    with np.errstate(all="ignore"):
        value = f(x)
        for _ in range(NEWTON_ITERATIONS):
            norm = np.linalg.norm(value)
            if not np.isfinite(norm) or norm < 1e-12:
                break
            step = np.linalg.lstsq(np.nan_to_num(jac(x)[:, free]), -value, rcond=None)[0]
            for _ in range(30):
                trial = x.copy()
                trial[free] += step
                trial_value = f(trial)
                if np.linalg.norm(trial_value) < norm:
                    break
                step = step / 2
            else:
                break
            x, value = trial, trial_value
    return x
