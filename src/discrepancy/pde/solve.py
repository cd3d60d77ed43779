"""The sparse regression of a PDE fit: supports chosen by purged blocked cross-validation.

The statistics are kept per *segment* of consecutive snapshots, each at least one time
window long (a derivative stencil, or a test function's support). Segments are dealt to
``N_FOLDS`` folds in turn; fold ``f`` is predicted by a support fitted on every segment
that is neither in ``f`` nor next to one of its segments. Rows of a segment and of its
neighbours share samples (weak-form rows integrate ``2 H + 1`` of them), so without this
purge a fold's noise is also in its training data and spurious terms look predictive
(Schrodinger's equation at 1 % noise: 19 spurious terms when test functions spanned several
blocks); rows two segments apart share none. This is the "hv-block" cross-validation of
Racine (2000), from per-segment Gram statistics.

Candidates are the supports along STLSQ's threshold path and along backward elimination
(:mod:`discrepancy.optimizers.backward`: PDE libraries hold collinear columns on which the
threshold path alone missed a two-field reaction's support). The choice is the sparsest
support within one standard error of the best, fold errors floored at :data:`FLOOR` of the
mean square ``u_t`` (spatial derivatives of sampled fields, and fields from solvers of
finite order, are rarely consistent to better than a relative 1e-4); coefficients are the
least-squares refit on it. Other optimizers (or a fixed threshold) are fitted as given.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import DataError
from ..optimizers import STLSQ, GramStatistics, solve_normal
from ..optimizers.backward import backward_path
from ..optimizers.selection import threshold_path

N_FOLDS = 5
#: fold errors below FLOOR times the mean square ``u_t`` count as numerical
FLOOR = 1e-8


def solve(optimizer, stats: GramStatistics):
    """Fit ``optimizer`` (a copy the caller owns) on ``stats``; returns it."""
    auto = isinstance(optimizer, STLSQ) and optimizer.threshold == "auto" and \
        optimizer.constraints is None and not optimizer.normalize_columns
    if not auto:
        return optimizer.fit_statistics(_total(stats))
    optimizer._validate_params()
    if not all(np.all(np.isfinite(a)) for a in (stats.gram, stats.rhs, stats.yy)):
        raise DataError("the statistics hold non-finite values: the library or the targets "
                        "overflowed on these data (scale the fields or use a smaller library)")
    segments = stats.folds or []
    if len(stats.usable_folds()) < 3:
        raise DataError(f"choosing the terms cross-validates over segments of whole time "
                        f"windows and needs at least 3; these data have "
                        f"{len(stats.usable_folds())} (give longer runs, or a fixed threshold: "
                        "STLSQ(threshold=0.05))")
    p, n = stats.rhs.shape
    coef, selection = np.zeros((n, p)), []
    for i in range(n):
        candidates = _candidates(optimizer, stats, i)
        errors = np.array([_fold_errors(stats, segments, i, s) for s in candidates])
        floor = FLOOR * max(stats.signal[i], stats.yy[i]) / stats.count
        errors = np.maximum(errors, floor)
        mean, se = errors.mean(axis=1), errors.std(axis=1, ddof=1) / np.sqrt(errors.shape[1])
        best = int(np.argmin(mean))
        ok = [j for j in range(len(candidates)) if mean[j] <= mean[best] + se[best]]
        pick = min(ok, key=lambda j: (candidates[j].sum(), mean[j]))
        coef[i] = _refit(stats.gram, stats.rhs[:, i], candidates[pick])
        selection.append({"n_terms": [int(s.sum()) for s in candidates],
                          "error": mean.tolist(), "error_se": se.tolist(),
                          "criterion": "purged blocked cross-validation", "chosen": pick})
    optimizer.coef_, optimizer.selection_ = coef, selection
    optimizer.thresholds_ = np.full(n, np.nan)
    optimizer.ind_ = coef != 0
    return optimizer


def _total(stats: GramStatistics) -> GramStatistics:
    """The sums alone (an optimizer's own selection would treat segments as its folds)."""
    out = GramStatistics(stats.p, stats.n)
    out.gram, out.rhs, out.yy, out.signal = stats.gram, stats.rhs, stats.yy, stats.signal
    out.count = stats.count
    return out


def _candidates(optimizer, stats, i) -> list[np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = [s for _, s in threshold_path(optimizer, stats.gram, stats.rhs[:, i])]
    seen = {s.tobytes() for s in found}
    for s in backward_path(stats.gram, stats.rhs[:, i]):
        if s.tobytes() not in seen:
            seen.add(s.tobytes())
            found.append(s)
    return found


def _refit(gram, rhs, support) -> np.ndarray:
    coef = np.zeros(len(rhs))
    if support.any():
        coef[support] = solve_normal(gram[np.ix_(support, support)], rhs[support])
    return coef


def _fold_errors(stats, segments, i, support) -> np.ndarray:
    """Mean squared error of target ``i`` on each fold, the support fitted on the segments
    neither in the fold nor next to it."""
    k = len(segments)
    folds = min(N_FOLDS, k)
    out = np.empty(folds)
    for f in range(folds):
        test = [j for j in range(k) if j % folds == f]
        purge = {j + d for j in test for d in (-1, 1)} - set(test)
        drop = [segments[j] for j in sorted(set(test) | purge) if 0 <= j < k]
        gram = stats.gram - sum(s.gram for s in drop)
        rhs = stats.rhs[:, i] - sum(s.rhs[:, i] for s in drop)
        c = _refit(gram, rhs, support)
        sq = sum(segments[j].yy[i] - 2 * c @ segments[j].rhs[:, i] + c @ segments[j].gram @ c
                 for j in test)
        count = sum(segments[j].count for j in test)
        out[f] = max(sq, 0.0) / max(count, 1)
    return out
