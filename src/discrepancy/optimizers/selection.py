"""Choosing the STLSQ threshold from the data (no hand tuning).

For each target the threshold path is walked from the full model to the empty one: every
threshold just above a coefficient of the ridge solution gives one candidate support. Each
support is scored by cross-validation over contiguous blocks of samples: the statistics
keep ``ΘᵀΘ``, ``Θᵀy``, ``yᵀy`` per fold (segments of consecutive rows dealt to the folds
in turn), so fold ``f`` is predicted by the support's least-squares fit on the other folds
(their statistics are the total minus fold ``f``'s) at the cost of a small solve.

Why blocks and not an information criterion: smoothing and differentiating make the
residuals of neighbouring samples strongly correlated, so a criterion that counts every
sample as independent (BIC) keeps adding terms when the smoothing window is wide. A
held-out block is predicted from samples whose noise it does not share (segments span at
least two smoothing windows), so spurious terms do not help there.

The choice is the sparsest support whose error is within one standard error (over folds)
of the best (the "one-standard-error rule"), with every fold's error floored at
:data:`FLOOR` times the mean square of the derivatives (or of the targets, if larger): on
noise-free data, terms that improve the fit only below that level are numerical error of
the derivative, or rounding in the error's own computation from sums (which loses about
``eps * yᵀy``), not dynamics, so exact data give exactly sparse models. Without folds
(``fit_gram`` given only totals) the Bayesian information criterion is used instead.
"""
from __future__ import annotations

import warnings
from copy import copy

import numpy as np
from scipy.stats import binomtest

from .base import refit_on_support, solve_normal
from .gram import residual_sum
from .linear_constraints import LinearConstraints

#: fold errors below FLOOR * mean(x_dot^2) are numerical (a relative RMS error of 1e-6)
FLOOR = 1e-12


def candidate_thresholds(gram: np.ndarray, rhs_column: np.ndarray, alpha: float,
                         allowed: np.ndarray | None = None) -> np.ndarray:
    """Thresholds just above each coefficient magnitude of the full ridge solution on the
    ``allowed`` terms (and 0)."""
    s = np.ones(len(rhs_column), bool) if allowed is None else allowed
    full = np.abs(solve_normal(gram[np.ix_(s, s)], rhs_column[s], alpha)) if s.any() \
        else np.zeros(0)
    levels = np.unique(full[full > 0])
    return np.concatenate([[0.0], levels * (1 + 1e-9)])


def bic(rss: float, k: int, m: int) -> float:
    """Bayesian information criterion of a Gaussian model with k terms on m samples."""
    return m * np.log(max(rss, 1e-300) / m) + k * np.log(m)


def threshold_path(stlsq, gram, rhs_column, mask=None) -> list[tuple[float, np.ndarray]]:
    """``(threshold, support)`` along the path, one entry per distinct support (sparser
    as the threshold grows; the last is empty). ``mask``: the target's ``LinearConstraints``
    of one equation (terms it may use)."""
    path, seen = [], set()
    allowed = None if mask is None else mask.allowed[0]
    for threshold in candidate_thresholds(gram, rhs_column, stlsq.alpha, allowed):
        solver = copy(stlsq)
        solver.threshold = float(threshold)
        with warnings.catch_warnings():  # an empty model is a legitimate candidate
            warnings.simplefilter("ignore")
            support = solver._solve_fixed(gram, rhs_column[:, None], mask)[0] != 0
        key = support.tobytes()
        if key not in seen:
            seen.add(key)
            path.append((float(threshold), support))
    return path


def cross_validated_errors(stats, i: int, support: np.ndarray, alpha: float) -> np.ndarray:
    """Mean squared error on each usable fold of target ``i``, the support fitted on the
    other folds, ``(K,)``."""
    folds = stats.usable_folds()
    errors = np.empty(len(folds))
    for k, fold in enumerate(folds):
        coef = refit_on_support(stats.gram - fold.gram, stats.rhs[:, i] - fold.rhs[:, i],
                                support, alpha)
        sq = residual_sum(fold.gram, fold.rhs[:, i], fold.yy[i], coef)
        errors[k] = max(sq, 0.0) / fold.count
    return errors


def floored_cv_errors(stats, i: int, support: np.ndarray, alpha: float) -> np.ndarray:
    """:func:`cross_validated_errors`, each floored at :data:`FLOOR` times the mean square
    of the derivatives (or of the targets, if larger): below it they are numerical."""
    floor = FLOOR * max(stats.signal[i], stats.yy[i]) / stats.count
    return np.maximum(cross_validated_errors(stats, i, support, alpha), floor)


def cross_validates(stats) -> bool:
    """Whether the statistics hold the two folds cross-validation needs; statistics with
    folds but too few samples for two fall back to BIC with a ShortRecordWarning
    (:func:`discrepancy.short_records.too_short`)."""
    if stats.folds is None:
        return False
    from ..short_records import too_short

    return not too_short(f"threshold='auto' (cross-validation over blocks of {stats.segment} "
                         "samples)", stats.count, stats.segment + 1,
                         fallback="the Bayesian information criterion") \
        and len(stats.usable_folds()) >= 2


def one_standard_error(error, se, sizes) -> int:
    """The one-standard-error rule: the index of the smallest model (``sizes``, ties broken
    by the lower error) whose mean ``error`` is within one standard error ``se`` of the
    best's. The one implementation of the rule (the threshold path here, forecast scores in
    :mod:`discrepancy.selection`, output-error supports in
    :mod:`discrepancy.models.outputs.output_fit`)."""
    error = np.asarray(error, dtype=float)
    best = int(np.argmin(error))
    ok = [j for j in range(len(error)) if error[j] <= error[best] + se[best]]
    return min(ok, key=lambda j: (sizes[j], error[j]))


#: one-sided level of the sign test a correction must pass against the prior alone
SIGN_LEVEL = 0.05


def clearly_better(errors, reference) -> bool:
    """Whether ``errors`` (per held-out block or forecast window) are lower than the
    ``reference``'s on the same blocks in a clear majority of them: a one-sided sign test
    at :data:`SIGN_LEVEL` (with 8 blocks, 7 must be better). A mean gain that a few blocks
    carry (a disturbance some terms happened to follow) fails it. Used by the
    prediction-error choice (:mod:`discrepancy.estimation.support_path`, 8 blocks per
    record); at fewer than 5 blocks no result can pass it."""
    errors, reference = np.asarray(errors, float), np.asarray(reference, float)
    wins = int(np.sum(errors < reference))
    return bool(binomtest(wins, len(reference), 0.5, alternative="greater").pvalue
                <= SIGN_LEVEL)


def select_thresholds(stlsq, stats, constraints=None) -> tuple[np.ndarray, np.ndarray,
                                                                 list[dict]]:
    """Per target, the selected STLSQ solution over the threshold path (within the
    ``constraints``' masks; their linear parts are for the caller's final refit).

    Returns ``(coef (n, p), thresholds (n,), selection)``; ``selection[i]`` describes the
    scored path of target ``i``: ``thresholds``, ``n_terms``, ``error`` (cross-validated
    mean squared error, or BIC), ``error_se``, ``criterion``, the ``chosen`` index and the
    ``supports`` (``(p,)`` bool each) along the path.
    """
    p, n = stats.rhs.shape
    coef, chosen_thresholds, selection = np.zeros((n, p)), np.zeros(n), []
    use_cv = cross_validates(stats)
    alpha = 0.0 if stlsq.unbias else stlsq.alpha
    for i in range(n):
        mask = None if constraints is None else LinearConstraints(
            1, p, constraints.allowed[i:i + 1].copy())
        path = threshold_path(stlsq, stats.gram, stats.rhs[:, i], mask)
        if use_cv:
            scores = [floored_cv_errors(stats, i, s, alpha) for _, s in path]
            error = np.array([e.mean() for e in scores])
            se = np.array([e.std(ddof=1) / np.sqrt(len(e)) for e in scores])
            pick = one_standard_error(error, se, [int(s.sum()) for _, s in path])
        else:  # residuals below FLOOR of the signal are numerical, as in the folds
            floor = FLOOR * max(stats.signal[i], stats.yy[i])
            error = np.array([bic(max(_rss(stats, i, refit_on_support(
                stats.gram, stats.rhs[:, i], s, alpha)), floor), int(s.sum()), stats.count)
                for _, s in path])
            se = np.zeros_like(error)
            pick = int(np.argmin(error))
        threshold, support = path[pick]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            solver = copy(stlsq)
            solver.threshold = threshold
            coef[i] = solver._solve_fixed(stats.gram, stats.rhs[:, i:i + 1], mask)[0]
        chosen_thresholds[i] = threshold
        selection.append({"thresholds": [t for t, _ in path],
                          "n_terms": [int(s.sum()) for _, s in path],
                          "error": error.tolist(), "error_se": se.tolist(),
                          "criterion": "blocked cross-validation" if use_cv else "BIC",
                          "chosen": pick, "supports": [s.copy() for _, s in path]})
    return coef, chosen_thresholds, selection


def _rss(stats, i, coef) -> float:
    return float(residual_sum(stats.gram, stats.rhs[:, i], stats.yy[i], coef))
