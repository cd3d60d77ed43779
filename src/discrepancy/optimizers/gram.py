"""Gram statistics: the sums over samples that every regression here needs.

``ΘᵀΘ`` (p×p), ``Θᵀy`` (p×n), ``yᵀy`` (n) and the sample count are additive, so
they can be accumulated chunk by chunk, merged across workers, and handed to
the solvers, which only ever see p×p systems.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ShapeError


@dataclass
class GramStatistics:
    """Running sums for ``p`` features and ``n`` targets.

    Attributes:
        gram: ``ΘᵀΘ``, ``(p, p)``.
        rhs: ``Θᵀy``, ``(p, n)``.
        yy: ``Σ y²`` per target, ``(n,)``.
        count: number of samples added.
    """

    p: int
    n: int
    gram: np.ndarray = field(init=False)
    rhs: np.ndarray = field(init=False)
    yy: np.ndarray = field(init=False)
    count: int = 0

    def __post_init__(self):
        self.gram = np.zeros((self.p, self.p))
        self.rhs = np.zeros((self.p, self.n))
        self.yy = np.zeros(self.n)

    def add(self, theta: np.ndarray, y: np.ndarray) -> GramStatistics:
        """Add the rows of ``theta`` ``(m, p)`` and ``y`` ``(m, n)``."""
        if theta.shape[1] != self.p or y.shape[1] != self.n or theta.shape[0] != y.shape[0]:
            raise ShapeError(f"chunk must be theta (m, {self.p}) and y (m, {self.n}); "
                             f"got {theta.shape} and {y.shape}")
        self.gram += theta.T @ theta
        self.rhs += theta.T @ y
        self.yy += np.einsum("ij,ij->j", y, y)
        self.count += theta.shape[0]
        return self

    def __iadd__(self, other: GramStatistics) -> GramStatistics:
        """Add ``other``'s sums into these, in place."""
        if (other.p, other.n) != (self.p, self.n):
            raise ShapeError(f"cannot merge statistics of ({other.p}, {other.n}) into "
                             f"({self.p}, {self.n})")
        self.gram += other.gram
        self.rhs += other.rhs
        self.yy += other.yy
        self.count += other.count
        return self

    def merge(self, other: GramStatistics) -> GramStatistics:
        """Sum of two statistics (e.g. from two workers), as a new object."""
        out = GramStatistics(self.p, self.n)
        out += self
        out += other
        return out

    def residual_sum_of_squares(self, coef: np.ndarray) -> np.ndarray:
        """``Σ (y - Θ ξ)²`` per target for ``coef`` ``(n, p)``, from the sums alone."""
        cross = np.einsum("pn,np->n", self.rhs, coef)
        quad = np.einsum("np,pq,nq->n", coef, self.gram, coef)
        return np.maximum(self.yy - 2 * cross + quad, 0.0)
