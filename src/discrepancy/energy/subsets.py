"""Which terms a friction law keeps: candidate supports and the rule that chooses among them.

Candidate supports of up to ``max_terms`` terms come from the fit's own statistics
(:mod:`.regression`): every subset when there are at most ``EXHAUSTIVE`` of them, otherwise
the supports met by forward selection (add the term that lowers the constrained loss most)
and by backward elimination from the constrained fit of the whole library (drop the term
whose removal raises it least). Each candidate is then scored as the procedure asks: the
training error after a moving average (``holdout = 0``) or the largest error with which a
fit on the first ``1 - holdout`` continues over the rest. Stepwise paths replaced the
exhaustive search (793 subsets of a three-link library, per fit) because the blind protocol
runs hundreds of fits; on libraries small enough for both they are compared in the tests.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations
from math import comb

import numpy as np
from scipy.ndimage import uniform_filter1d

from ..constraints import Integral, Interval, check_argument
from ..data.validation import check_array
from ..errors import ParameterError
from .regression import statistics
from .soundness import Limits

#: largest number of subsets searched exhaustively
EXHAUSTIVE = 200


def _constraints(limits, subset):
    return (None, None) if limits is None else limits.constraints(subset)


def candidate_supports(stats, p: int, max_terms: int, limits=None) -> list[tuple[int, ...]]:
    """Supports (sorted index tuples) to score, from the statistics ``stats`` of the fit."""
    if sum(comb(p, k) for k in range(1, max_terms + 1)) <= EXHAUSTIVE:
        return [s for k in range(1, max_terms + 1) for s in combinations(range(p), k)]

    def loss(subset):
        return stats.fit(subset, *_constraints(limits, subset))[1]

    found = set()
    support: tuple[int, ...] = ()
    for _ in range(max_terms):              # forward selection
        trials = [tuple(sorted((*support, j))) for j in range(p) if j not in support]
        support = min(trials, key=loss)
        found.add(support)
    full = tuple(range(p))                 # backward elimination from the whole library
    xi = stats.fit(full, *_constraints(limits, full))[0]
    support = tuple(j for j, c in zip(full, xi, strict=True) if c > 0) or full
    while support:
        if len(support) <= max_terms:
            found.add(support)
        if len(support) == 1:
            break
        support = min((tuple(j for j in support if j != drop) for drop in support), key=loss)
    return sorted(found, key=lambda s: (len(s), s))


def select_terms(features: np.ndarray, delta_h: np.ndarray, *, max_terms: int = 4,
                 holdout: float = 0.0, tolerance: float = 0.02, block: int | None = None,
                 limits=None, statistics_of=None) -> tuple[tuple[int, ...], list]:
    """Best non-negative, sound support of at most ``max_terms`` columns.

    Score of a support: with ``holdout = 0`` the RMS training error (J) after a moving
    average over 1 % of the samples (the cumulative model is smooth; the pointwise noise of
    ``H_m`` from differentiated angles would otherwise hide what a term adds); with
    ``holdout = h`` the support is fitted on the first ``1 - h`` of the samples and scored
    by the largest error with which it continues over the last ``h``, relative to that
    part's own ``dH`` range (the task a later validation window poses). Supports in which a
    coefficient is 0 duplicate a smaller one and are skipped. The size grows from 1 while
    the best score of the next size is lower by more than the fraction ``tolerance`` (an
    elbow rule: the cumulative features are strongly correlated, so noise alone lowers the
    error a little with every term). ``block`` chooses the fit (:mod:`.regression`);
    ``limits`` (:class:`~discrepancy.energy.soundness.Limits` of all columns) are
    constraints of every fit; ``statistics_of(n)``, when given, returns the statistics of
    the first ``n`` samples (shared between procedures; default: computed here).

    Returns ``(support, candidates)`` with ``candidates`` the sorted ``(score, support)``
    list; ``support`` is empty when no law fits with positive coefficients.
    """
    features = check_array("features", features, allow_1d=True)
    delta_h = check_array("delta_h", delta_h, ndim=1, n_rows=features.shape[0])
    m, p = features.shape
    check_argument("max_terms", max_terms, Interval(Integral, 1))
    max_terms = min(int(max_terms), p)
    if not 0 <= holdout < 0.9:
        raise ParameterError(f"holdout must be a fraction in [0, 0.9); got {holdout}")
    cut = int(round(m * (1 - holdout)))
    stats = statistics(features[:cut], delta_h[:cut], block) if statistics_of is None else \
        statistics_of(cut)
    smooth = max(1, m // 100)
    candidates = []
    for subset in candidate_supports(stats, p, max_terms, limits):
        xi, _ = stats.fit(subset, *_constraints(limits, subset))
        if np.any(xi <= 0):
            continue
        error = delta_h - stats.offset(subset, xi) - features[:, list(subset)] @ xi
        if holdout > 0:
            score = np.max(np.abs(error[cut:])) / max(np.ptp(delta_h[cut:]), 1e-300)
        else:
            score = np.sqrt(np.mean(uniform_filter1d(error, smooth) ** 2))
        candidates.append((float(score), subset))
    candidates.sort()
    best = {}
    for score, subset in candidates:
        best.setdefault(len(subset), (score, subset))
    if not best:    # every law needs a negative coefficient: the data show no dissipation
        return (), candidates
    # errors below ~1e-5 of dH's spread are the trapezoid rule's, not information
    floor = 1e-5 if holdout > 0 else 1e-5 * float(np.std(delta_h))
    sizes = sorted(best)
    chosen = sizes[0]
    for k in sizes[1:]:
        if best[chosen][0] > floor and best[k][0] < best[chosen][0] * (1 - tolerance):
            chosen = k
        else:
            break
    return best[chosen][1], candidates


@dataclass(frozen=True)
class DissipationFit:
    """Result of :func:`fit_dissipation`: the chosen terms, their coefficients and offset.

    Attributes:
        terms, coefficients (``(k,)``, each term's unit), offset (J).
        candidates: ``(score, names)`` of every support scored.
        limits: the soundness constraints of the chosen terms (``None``: unconstrained).
        active: the kinds of constraint that hold the law at its bound.
    """

    terms: tuple
    coefficients: np.ndarray
    offset: float
    candidates: list
    limits: Limits | None = None
    active: tuple[str, ...] = ()


def fit_dissipation(features: np.ndarray, delta_h: np.ndarray, terms, *, limits=None,
                    **selection) -> DissipationFit:
    """Select terms (:func:`select_terms`) and refit them on all samples under ``limits``;
    terms refitted to 0 are dropped."""
    support, candidates = select_terms(features, delta_h, limits=limits, **selection)
    of = selection.get("statistics_of")
    stats = statistics(features, delta_h, selection.get("block")) if of is None else \
        of(len(delta_h))

    def refit(subset):
        xi = stats.fit(subset, *_constraints(limits, subset))[0] if subset else np.zeros(0)
        return xi, stats.offset(subset, xi) if subset else float(np.mean(delta_h))

    xi, offset = refit(support)
    if np.any(xi <= 0):
        support = tuple(j for j, c in zip(support, xi, strict=True) if c > 0)
        xi, offset = refit(support)
    named = [(s, [terms[i].name for i in sub]) for s, sub in candidates]
    chosen = None if limits is None else limits.restricted(support)
    active = () if limits is None else tuple(limits.active(support, xi))
    return DissipationFit(tuple(terms[i] for i in support), xi, float(offset), named,
                          chosen, active)
