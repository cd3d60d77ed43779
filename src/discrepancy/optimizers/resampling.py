"""Resampled Gram statistics: one machinery for bootstraps and ensembles.

A resample weighs units of the data by multiplicities (how often each was drawn) and asks
for the statistics of the weighted data, folds included, so that every solver (also the
automatic threshold, which cross-validates over the folds) runs on it unchanged. Units are
either rows (:class:`Rows`: the samples themselves, kept in memory when a solver needs them,
as PySINDy's ensembles bag samples) or blocks of rows summarised by their own Gram
statistics (:func:`from_blocks`: what the model's block bootstrap resamples, at the cost of
``p × p`` per block). Both end in the same :class:`~discrepancy.optimizers.GramStatistics`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .gram import GramStatistics


@dataclass
class Rows:
    """The regression's rows, kept beside the statistics for solvers that need them.

    Attributes:
        theta: ``(m, p)``; y: ``(m, n)``; signal: ``(m, n)`` (the derivatives ``ẋ``, as
            in :class:`GramStatistics`); weight: ``(m,)`` sample weights or None;
        fold: ``(m,)`` the cross-validation fold of each row (as in the statistics).
    """

    theta: np.ndarray
    y: np.ndarray
    signal: np.ndarray
    weight: np.ndarray | None
    fold: np.ndarray

    @property
    def n_rows(self) -> int:
        """Number of rows ``m``."""
        return self.theta.shape[0]

    def weighted(self) -> tuple[np.ndarray, np.ndarray]:
        """``(Θ √w, y √w)``: the rows as a least-squares problem."""
        if self.weight is None:
            return self.theta, self.y
        root = np.sqrt(self.weight)[:, None]
        return self.theta * root, self.y * root

    def scaled(self, scale: np.ndarray) -> Rows:
        """The same rows with each column of ``theta`` multiplied by ``scale`` ``(p,)``
        (``y``, ``signal``, weights and folds unchanged)."""
        return Rows(self.theta * scale[None, :], self.y, self.signal, self.weight, self.fold)

    def __add__(self, other: Rows) -> Rows:
        def cat(a, b):
            return None if a is None or b is None else np.concatenate([a, b])
        weight = None if self.weight is None and other.weight is None else np.concatenate(
            [np.ones(self.n_rows) if self.weight is None else self.weight,
             np.ones(other.n_rows) if other.weight is None else other.weight])
        return Rows(cat(self.theta, other.theta), cat(self.y, other.y),
                    cat(self.signal, other.signal), weight, cat(self.fold, other.fold))

    def statistics(self, multiplicity: np.ndarray, like: GramStatistics,
                   columns: np.ndarray | None = None) -> GramStatistics:
        """The statistics of the rows taken ``multiplicity`` ``(m,)`` times each (and only
        the library ``columns``, when given), with folds like ``like``'s."""
        w = multiplicity * (1.0 if self.weight is None else self.weight)
        theta = self.theta if columns is None else self.theta[:, columns]
        sums = [_sums(theta[pick], self.y[pick], self.signal[pick], w[pick],
                      multiplicity[pick].sum())
                for pick in (self.fold == f for f in range(max(like.n_folds, 1)))]
        return from_blocks(*(np.stack(parts) for parts in zip(*sums, strict=True)),
                           np.arange(len(sums)), like)


def _sums(theta, y, signal, w, count):
    wt = theta * w[:, None]
    return (wt.T @ theta, wt.T @ y, np.einsum("i,ij,ij->j", w, y, y),
            np.einsum("i,ij,ij->j", w, signal, signal), float(count))


def from_blocks(gram, rhs, yy, signal, counts, folds, like: GramStatistics) -> GramStatistics:
    """GramStatistics (with ``like``'s folds) from per-block sums ``(B, ...)``; ``folds``
    ``(B,)`` is each block's fold and ``counts`` ``(B,)`` its rows (times how often it was
    drawn)."""
    stats = GramStatistics(gram.shape[1], rhs.shape[2], like.n_folds, like.segment)
    if not like.n_folds:
        stats.gram, stats.rhs = gram.sum(0), rhs.sum(0)
        stats.yy, stats.signal, stats.count = yy.sum(0), signal.sum(0), int(round(counts.sum()))
        return stats
    for f, fold in enumerate(stats.folds):
        pick = folds == f
        fold.gram, fold.rhs = gram[pick].sum(0), rhs[pick].sum(0)
        fold.yy, fold.signal = yy[pick].sum(0), signal[pick].sum(0)
        fold.count = int(round(counts[pick].sum()))
    stats._sum_folds()
    return stats


def restricted(stats: GramStatistics, columns: np.ndarray) -> GramStatistics:
    """The statistics of the library ``columns`` only (folds and rows included)."""
    out = GramStatistics(len(columns), stats.n, stats.n_folds, stats.segment)
    for new, old in zip([out, *(out.folds or [])], [stats, *(stats.folds or [])], strict=True):
        new.gram = old.gram[np.ix_(columns, columns)]
        new.rhs = old.rhs[columns]
        new.yy, new.signal, new.count = old.yy, old.signal, old.count
    if stats.rows is not None:
        r = stats.rows
        out.rows = Rows(r.theta[:, columns], r.y, r.signal, r.weight, r.fold)
    return out
