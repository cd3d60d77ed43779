"""Gram statistics: the sums over samples that every regression here needs.

``ΘᵀΘ`` (p×p), ``Θᵀy`` (p×n), ``yᵀy`` (n), ``Σ ẋ²`` (n) and the sample count are
additive, so they can be accumulated chunk by chunk, merged across workers, and handed to
the solvers, which only ever see p×p systems. The same sums are also kept per *fold*
(rows cut into contiguous segments dealt to ``n_folds`` folds in turn), so that
cross-validation of a sparse model costs p×p solves too: a fold's training statistics
are the total minus the fold's own.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..constraints import Integral, Interval
from ..errors import ShapeError
from ..resources import ALWAYS_ALLOWED, check_memory

#: what p, n, n_folds and segment may be
SIZE = Interval(Integral, 0)


def residual_sum(gram: np.ndarray, rhs: np.ndarray, yy, coef: np.ndarray):
    """``Σ (y - Θ ξ)²`` of one target from its sums: ``yy - 2 ξᵀ Θᵀy + ξᵀ ΘᵀΘ ξ``, with
    ``gram`` ``(p, p)``, ``rhs`` ``(p,)``, ``yy`` a number and ``coef`` ``(p,)`` on the same
    terms. Not clipped at 0: rounding can leave a perfect fit slightly negative."""
    return yy - 2 * coef @ rhs + coef @ gram @ coef


@dataclass
class GramStatistics:
    """Running sums for ``p`` features and ``n`` targets.

    Attributes:
        gram: ``ΘᵀΘ``, ``(p, p)``.
        rhs: ``Θᵀy``, ``(p, n)``.
        yy: ``Σ y²`` per target, ``(n,)``.
        signal: ``Σ ẋ²`` per target, ``(n,)``: the size of what the whole model predicts
            (``y`` plus the prior), against which the selection judges what is negligible;
            equal to ``yy`` when no prior was subtracted.
        count: number of samples added.
        folds: the same sums per cross-validation fold (a list of ``n_folds``
            GramStatistics), or ``None`` when not kept.
        segment: rows per contiguous segment of the fold assignment (row ``i`` of the data,
            counted over all trajectories in order, is in fold ``(i // segment) % n_folds``).
        rows: the rows themselves (:class:`~discrepancy.optimizers.resampling.Rows`), kept
            only for solvers that need them (``needs_rows``: trimming, bagging samples).
        held_out: samples kept beside the sums by whoever feeds them (a model's fit keeps
            forecast windows and the range of every variable there,
            :class:`discrepancy.selection.held_out.HeldOutWindows`), or ``None``; merged by
            ``+=``, never read by the solvers.
    """

    p: int
    n: int
    n_folds: int = 0
    segment: int = 0
    gram: np.ndarray = field(init=False)
    rhs: np.ndarray = field(init=False)
    yy: np.ndarray = field(init=False)
    signal: np.ndarray = field(init=False)
    count: int = 0
    folds: list | None = field(init=False, default=None)
    rows: object = field(init=False, default=None, repr=False)
    held_out: object | None = field(init=False, default=None)

    def __post_init__(self):
        sizes = {"p": self.p, "n": self.n, "n_folds": self.n_folds, "segment": self.segment}
        if not all(type(v) is int and v >= 0 for v in sizes.values()):  # fast path: valid
            from ..constraints import validate_params
            validate_params("GramStatistics", sizes, {k: [SIZE] for k in sizes})
        size = 8 * (self.n_folds + 1) * self.p * (self.p + self.n)
        if size > ALWAYS_ALLOWED:  # (the message is only formatted for large sizes)
            check_memory(f"Gram statistics of {self.p} columns", size, "Use fewer columns")
        self.gram = np.zeros((self.p, self.p))
        self.rhs = np.zeros((self.p, self.n))
        self.yy = np.zeros(self.n)
        self.signal = np.zeros(self.n)
        if self.n_folds:
            if self.segment < 1:
                raise ShapeError(f"segment must be >= 1 row with folds; got {self.segment}")
            self.folds = [GramStatistics(self.p, self.n) for _ in range(self.n_folds)]

    def add(self, theta: np.ndarray, y: np.ndarray, signal: np.ndarray | None = None,
            weight: np.ndarray | None = None, *, first_row: int = 0) -> GramStatistics:
        """Add the rows of ``theta`` ``(m, p)`` and ``y`` ``(m, n)`` (and ``signal`` = ``ẋ``
        ``(m, n)``, default ``y``; row weights ``(m,)``, default 1); ``first_row`` is the
        data row of ``theta[0]`` (for folds)."""
        if theta.shape[1] != self.p or y.shape[1] != self.n or theta.shape[0] != y.shape[0]:
            raise ShapeError(f"chunk must be theta (m, {self.p}) and y (m, {self.n}); "
                             f"got {theta.shape} and {y.shape}")
        if weight is not None:
            root = np.sqrt(weight)[:, None]
            theta, y = theta * root, y * root
            signal = None if signal is None else signal * root
        if self.folds is not None:
            for lo, hi, fold in self.pieces(first_row, theta.shape[0]):
                self.folds[fold].add(theta[lo:hi], y[lo:hi],
                                     y[lo:hi] if signal is None else signal[lo:hi])
            self._sum_folds()
            return self
        self.gram += theta.T @ theta
        self.rhs += theta.T @ y
        self.yy += np.einsum("ij,ij->j", y, y)
        s = y if signal is None else signal
        self.signal += np.einsum("ij,ij->j", s, s)
        self.count += theta.shape[0]
        return self

    def pieces(self, first_row: int, m: int):
        """``(lo, hi, fold)`` for rows ``lo:hi`` of an array whose row 0 is data row
        ``first_row``: each piece lies in one segment."""
        lo = 0
        while lo < m:
            row = first_row + lo
            hi = min(m, lo + self.segment - row % self.segment)
            yield lo, hi, (row // self.segment) % self.n_folds
            lo = hi

    def _sum_folds(self) -> None:
        """Totals as the sums of the folds (one summation order, whatever the arrival)."""
        self.gram = sum(f.gram for f in self.folds)
        self.rhs = sum(f.rhs for f in self.folds)
        self.yy = sum(f.yy for f in self.folds)
        self.signal = sum(f.signal for f in self.folds)
        self.count = sum(f.count for f in self.folds)

    def __iadd__(self, other: GramStatistics) -> GramStatistics:
        """Add ``other``'s sums (and folds) into these, in place."""
        if (other.p, other.n, other.n_folds, other.segment) != \
                (self.p, self.n, self.n_folds, self.segment):
            raise ShapeError(f"cannot merge statistics of (p={other.p}, n={other.n}, "
                             f"{other.n_folds} folds of {other.segment} rows) into (p={self.p}, "
                             f"n={self.n}, {self.n_folds} folds of {self.segment} rows)")
        if other.rows is not None:  # rows are kept beside the sums, not summed with them
            self.rows = other.rows if self.rows is None else self.rows + other.rows
        if other.held_out is not None:
            if self.held_out is None:
                self.held_out = other.held_out.empty_like()
            self.held_out.merge(other.held_out)
        if self.folds is not None:
            for mine, theirs in zip(self.folds, other.folds, strict=True):
                mine += theirs
            self._sum_folds()
            return self
        self.gram += other.gram
        self.rhs += other.rhs
        self.yy += other.yy
        self.signal += other.signal
        self.count += other.count
        return self

    def merge(self, other: GramStatistics) -> GramStatistics:
        """Sum of two statistics (e.g. from two workers), as a new object."""
        out = self.empty_like()
        out += self
        out += other
        return out

    def empty_like(self) -> GramStatistics:
        """Empty statistics of the same size, folds and segment length (to accumulate into)."""
        return GramStatistics(self.p, self.n, self.n_folds, self.segment)

    def scaled(self, scale: np.ndarray) -> GramStatistics:
        """The statistics of the columns ``Θ * scale`` (folds included)."""
        out = self.empty_like()
        for new, old in zip([out, *(out.folds or [])], [self, *(self.folds or [])],
                            strict=True):
            new.gram = old.gram * np.outer(scale, scale)
            new.rhs = old.rhs * scale[:, None]
            new.yy, new.signal, new.count = old.yy, old.signal, old.count
        out.rows = None if self.rows is None else self.rows.scaled(scale)
        return out

    def usable_folds(self) -> list[GramStatistics]:
        """The folds that hold samples (cross-validation needs at least two)."""
        return [f for f in (self.folds or []) if f.count > 0]

    def residual_sum_of_squares(self, coef: np.ndarray) -> np.ndarray:
        """``Σ (y - Θ ξ)²`` per target for ``coef`` ``(n, p)``, from the sums alone."""
        return np.maximum([residual_sum(self.gram, self.rhs[:, i], self.yy[i], c)
                           for i, c in enumerate(coef)], 0.0)

    def to_vector(self) -> np.ndarray:
        """All sums in one flat array (folds included), for shipping between processes."""
        parts = [self] if self.folds is None else self.folds
        return np.concatenate([np.concatenate([s.gram.ravel(), s.rhs.ravel(), s.yy, s.signal,
                                               [s.count]]) for s in parts])

    def from_vector(self, v: np.ndarray) -> GramStatistics:
        """Statistics shaped like these with the sums of :meth:`to_vector` output."""
        out = self.empty_like()
        parts = [out] if out.folds is None else out.folds
        size = self.p * self.p + self.p * self.n + 2 * self.n + 1
        if v.shape != (size * len(parts),):
            raise ShapeError(f"expected {size * len(parts)} sums; got {v.shape}")
        for k, s in enumerate(parts):
            w = v[k * size:(k + 1) * size]
            a, b = self.p * self.p, self.p * self.p + self.p * self.n
            s.gram = w[:a].reshape(self.p, self.p).copy()
            s.rhs = w[a:b].reshape(self.p, self.n).copy()
            s.yy, s.signal = w[b:b + self.n].copy(), w[b + self.n:b + 2 * self.n].copy()
            s.count = int(round(w[-1]))
        if out.folds is not None:
            out._sum_folds()
        return out
