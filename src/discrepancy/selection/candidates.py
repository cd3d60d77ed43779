"""Whole-model candidates from per-equation paths, and their coefficients per fold.

Equation error proposes (cheap): the threshold path of each equation, scored by blocked
cross-validation (:mod:`discrepancy.optimizers.selection`), gives a few supports per
equation, from the cross-validated minimum down to no term. A whole model picks one support
per equation; forecasts couple the equations, so they are not chosen one by one. The
candidates are searched by coordinates: start from the equation-error choice, vary one
equation at a time over its path (everything else held), move to the best-forecasting
candidate and repeat from there (:func:`neighbours`). The prior alone (every equation
empty) is always a candidate.

Each candidate is refitted on the statistics of all folds but one (the total minus that
fold's sums), once per fold: a window whose origin lies in fold ``f`` is forecast by the
coefficients fitted without it.
"""
from __future__ import annotations

import numpy as np

from ..optimizers.base import refit_on_support
from ..optimizers.linear_constraints import constrained_solve
from ..optimizers.selection import floored_cv_errors

#: supports per equation offered to forecasts at most (the empty one included)
MAX_PER_EQUATION = 8
#: terms of the largest support added by forward selection (:func:`forward_supports`)
FORWARD_TERMS = 2
#: standard errors (over folds) by which a forward step must lower the blocked
#: cross-validation error to be offered
CV_MARGIN = 2.0
#: ... and by at least this fraction of its error
CV_GAIN = 0.01


def equation_paths(optimizer, n: int, p: int, stats=None, allowed=None,
                   alpha: float = 0.0) -> list[list[np.ndarray]]:
    """Per equation, the supports ``(p,)`` offered to forecasts: the optimizer's threshold
    path from its cross-validated minimum (the densest worth trying) to the empty support,
    sparser last, at most :data:`MAX_PER_EQUATION` (those nearest the equation-error
    choice, and the empty one); with ``stats`` (with folds), also the supports of forward
    selection (:func:`forward_supports`) that the path lacks, as far as each step
    cross-validates clearly better, before the empty one (a step that does not only offers
    forecasts more noise to fit). Raises LookupError when the optimizer kept no scored
    path."""
    paths = getattr(optimizer, "selection_", None)
    if not paths or any("supports" not in path for path in paths) or \
            paths[0].get("criterion") == "BIC":
        raise LookupError("no cross-validated threshold path")
    out = []
    for path in paths:
        best, chosen = int(np.argmin(path["error"])), int(path["chosen"])
        keep = range(best, len(path["supports"]))
        if len(keep) > MAX_PER_EQUATION:   # the nearest to the equation-error choice
            keep = sorted(sorted(keep, key=lambda j: abs(j - chosen))[:MAX_PER_EQUATION - 1])
        supports = [np.asarray(path["supports"][j], bool) for j in keep]
        if not supports[-1].any():
            supports.pop()
        if stats is not None and stats.folds:
            supports += _forward_worth_trying(stats, len(out), supports, allowed, alpha)
        out.append([*supports, np.zeros(p, bool)])
    return out


def _forward_worth_trying(stats, i, path, allowed, alpha) -> list[np.ndarray]:
    """Forward selection's supports of equation ``i`` not on ``path``, as far as each
    cross-validates clearly better than the one before it (no term, for the first):
    its error lower on the same folds by more than :data:`CV_MARGIN` standard errors of
    the differences and by :data:`CV_GAIN` of the error. On Lorenz at 20 % noise, spurious
    single terms beat no term by 0.1-1.5 standard errors and 0.01-0.5 %, and a second term
    beside the true one by 0.01 %; a true damping on a forced Duffing oscillator at 10 %
    noise by 2.9-20 standard errors and 3.5-12 %."""
    mask = np.ones(stats.p, bool) if allowed is None else np.asarray(allowed[i], bool)
    before, out = floored_cv_errors(stats, i, np.zeros(stats.p, bool), alpha), []
    for support in forward_supports(stats.gram, stats.rhs[:, i], mask):
        errors = floored_cv_errors(stats, i, support, alpha)
        gain = before - errors
        if len(gain) < 2 or gain.mean() <= max(CV_MARGIN * gain.std(ddof=1) / np.sqrt(
                len(gain)), CV_GAIN * before.mean()):
            break
        if not any(np.array_equal(support, s) for s in path):
            out.append(support)
        before = errors
    return out


def forward_supports(gram: np.ndarray, rhs: np.ndarray, allowed: np.ndarray
                     ) -> list[np.ndarray]:
    """Supports of 1 to :data:`FORWARD_TERMS` terms, each the last plus the term that
    explains most of the rest of one equation's residual (forward selection, from the sums
    ``gram`` ``(p, p)`` and ``rhs`` ``(p,)``). A threshold path drops a weak term before
    strong ones that stand in for it on the data (on a forced oscillator's periodic orbit,
    four input terms mimicked a damping of -0.05 x2 and simulated a new start four times
    worse than the prior); forward selection offers the term that fits alone."""
    support, out = np.zeros(len(rhs), bool), []
    diagonal = np.diag(gram)
    for _ in range(FORWARD_TERMS):
        best, gain = None, -np.inf
        for j in np.flatnonzero(allowed & ~support & (diagonal > 0)):
            trial = support.copy()
            trial[j] = True
            coef = refit_on_support(gram, rhs, trial)
            explained = float(coef[trial] @ rhs[trial])
            if np.isfinite(explained) and explained > gain:
                best, gain = j, explained
        if best is None:
            break
        support = support.copy()
        support[best] = True
        out.append(support)
    return out


def start(optimizer, paths) -> tuple[int, ...]:
    """The equation-error choice as path indices (its supports are on the paths)."""
    chosen = optimizer.coef_ != 0
    return tuple(next((j for j, s in enumerate(path) if np.array_equal(s, chosen[i])),
                      len(path) - 1) for i, path in enumerate(paths))


def prior_only(paths) -> tuple[int, ...]:
    """The prior-alone candidate as path indices: the last (empty) support of every equation."""
    return tuple(len(path) - 1 for path in paths)


def neighbours(centre: tuple[int, ...], paths) -> list[tuple[int, ...]]:
    """Candidates that differ from ``centre`` in one equation's support."""
    out = []
    for i, path in enumerate(paths):
        for j in range(len(path)):
            if j != centre[i]:
                out.append(centre[:i] + (j,) + centre[i + 1:])
    return out


def support_of(candidate: tuple[int, ...], paths) -> np.ndarray:
    """The terms of ``candidate`` (one path index per equation) as a bool array ``(n, p)``."""
    return np.array([paths[i][j] for i, j in enumerate(candidate)])


class FoldFits:
    """Coefficients of supports fitted on all folds but one, and on everything.

    Without linear constraints each equation is its own least squares (``alpha``: the
    optimizer's ridge when it does not refit unbiased), memoised by equation, support and
    fold; with them the constrained solve couples the equations.
    """

    def __init__(self, stats, constraints, alpha: float):
        self.stats, self.constraints, self.alpha = stats, constraints, alpha
        self.folds = stats.folds or []
        self._cache = {}

    def _system(self, fold: int | None):
        if fold is None:
            return self.stats.gram, self.stats.rhs
        f = self.folds[fold]
        return self.stats.gram - f.gram, self.stats.rhs - f.rhs

    def coefficients(self, support: np.ndarray, fold: int | None) -> np.ndarray:
        """``(n, p)`` for ``support`` ``(n, p)`` fitted without ``fold`` (None: on all)."""
        gram, rhs = self._system(fold)
        c = self.constraints
        if c is not None and c.has_linear:
            keep = support | (c.involved() & c.allowed)
            return constrained_solve(gram, rhs, keep, c)
        coef = np.zeros(support.shape)
        for i, s in enumerate(support):
            if s.any():
                key = (i, s.tobytes(), fold)
                if key not in self._cache:
                    self._cache[key] = refit_on_support(gram, rhs[:, i], s, self.alpha)[s]
                coef[i, s] = self._cache[key]
        return coef


def optimizer_fold_fits(optimizer, stats):
    """Coefficients ``{fold: (n, p)}`` of the optimizer itself refitted without each fold (a
    candidate that is an optimizer's answer rather than a support)."""
    import copy

    from ..optimizers.gram import GramStatistics

    out = {}
    for f, fold in enumerate(stats.folds or []):
        rest = GramStatistics(stats.p, stats.n)
        rest.gram, rest.rhs = stats.gram - fold.gram, stats.rhs - fold.rhs
        rest.yy, rest.signal = stats.yy - fold.yy, stats.signal - fold.signal
        rest.count = stats.count - fold.count
        out[f] = copy.deepcopy(optimizer).fit_statistics(rest).coef_
    return out
