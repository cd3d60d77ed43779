"""Choosing the terms of a prediction-error fit: a path of supports scored out of sample.

The path starts from every allowed term and removes one at a time (the smallest scaled
coefficient), refitting each support, down to none (the prior alone is always a
candidate). Each support is fitted on the first part of every record and scored on the
rest by forecasts from the filtered states (:mod:`~discrepancy.estimation.forecasts`; the
filter runs on, correcting its state with the measurements as it would in use); the
negative log-likelihood of the one-step innovations there is kept too. The standard error
comes from block means (errors of a misfitted model are correlated in time). The choice is
the sparsest support whose score is within one standard error of the best's, the standard
error of the *difference* taken over the same blocks (paired: the blocks a disturbance
makes hard are hard for every support, and cancel), or within ``tolerance`` (relative) of
the best score. Without ``tolerance``, a chosen support must also forecast better than the
prior alone in a clear majority of the blocks (a sign test), else the prior alone is
kept: under strong process noise one block can carry a mean gain of terms the system does
not have.

Seam: :func:`choose` is the one place that turns scored supports into a choice, so a
general forecast-based selection (scoring several origins and lead times) can replace it
without touching the fit; :class:`SupportScore` is the record both sides share.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optimizers.selection import clearly_better

#: contiguous blocks per record for the standard error of a held-out score
SCORE_BLOCKS = 8


@dataclass
class SupportScore:
    """One support on the path: its terms ``(n, p)`` bool, coefficients and noise levels
    fitted on the training part; the held-out score (mean scaled squared forecast error),
    its standard error and block means; the held-out and training mean negative
    log-likelihood of the innovations per sample."""

    support: np.ndarray
    coef: np.ndarray
    noise: np.ndarray
    heldout_score: float
    heldout_se: float
    heldout_blocks: np.ndarray | None
    heldout_nll: float
    training_nll: float

    @property
    def n_terms(self) -> int:
        """Number of terms in the support."""
        return int(self.support.sum())


def block_means(values: list[np.ndarray], blocks: int = SCORE_BLOCKS) -> np.ndarray:
    """Means of contiguous blocks of per-sample scores (one array per record); ``inf``
    where a score is not finite."""
    means = []
    for v in values:
        for b in np.array_split(v, min(blocks, len(v))):
            if len(b):
                means.append(b.mean() if np.all(np.isfinite(b)) else np.inf)
    return np.asarray(means)


def mean_and_se(means: np.ndarray) -> tuple[float, float]:
    """``(mean, standard error)`` of block means ``(b,)``: the standard error is
    ``std / √b`` (0 for a single block); ``(inf, inf)`` when any mean is not finite."""
    if not np.all(np.isfinite(means)):
        return np.inf, np.inf
    se = float(means.std(ddof=1) / np.sqrt(len(means))) if len(means) > 1 else 0.0
    return float(means.mean()), se


def choose(path: list[SupportScore], tolerance: float | None = None) -> SupportScore:
    """The sparsest support whose held-out score is within one (paired) standard error of
    the best (``tolerance=None``) or within ``tolerance`` (relative) of it."""
    best = min(path, key=lambda s: s.heldout_score)

    def close(s):
        if tolerance is not None:
            return s.heldout_score <= (1 + tolerance) * best.heldout_score
        if s.heldout_blocks is None or best.heldout_blocks is None:
            return s.heldout_score <= best.heldout_score + best.heldout_se
        excess, se = mean_and_se(s.heldout_blocks - best.heldout_blocks)
        return excess <= se

    pick = min((s for s in path if close(s)), key=lambda s: (s.n_terms, s.heldout_score))
    return pick if tolerance is not None else _unless_no_clear_gain(pick, path)


def _unless_no_clear_gain(pick: SupportScore, path: list[SupportScore]) -> SupportScore:
    """The prior alone instead of ``pick`` when ``pick`` does not forecast better in a clear
    majority of the held-out blocks (:func:`~discrepancy.optimizers.selection.clearly_better`)."""
    prior = next((s for s in path if s.n_terms == 0), None)
    if pick.n_terms == 0 or prior is None or pick.heldout_blocks is None \
            or prior.heldout_blocks is None:
        return pick
    return pick if clearly_better(pick.heldout_blocks, prior.heldout_blocks) else prior


def drop_least(support: np.ndarray, importance: np.ndarray,
               negligible: float = 1e-3) -> np.ndarray:
    """``support`` without its least important term (and any whose importance is below
    ``negligible`` of the largest)."""
    size = np.where(support, importance, np.inf)
    active = np.isfinite(size)
    drop = size <= negligible * size[active].max()
    drop[np.unravel_index(np.argmin(size), size.shape)] = True
    return support & ~drop
