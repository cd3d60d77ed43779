"""What filters return: the state of an online filter and the record of a whole run."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError


@dataclass(frozen=True)
class FilterState:
    """An online filter's belief: mean ``x`` ``(n,)`` and covariance ``P`` ``(n, n)``.

    ``innovation`` ``(k,)`` and ``innovation_cov`` ``(k, k)`` are those of the last update
    (``None`` before any; entries of missing outputs are 0 and 1). ``log_likelihood``: the
    sum over the updates so far of ``log p(y_k | y_0 ... y_{k-1})``.
    """

    x: np.ndarray
    P: np.ndarray
    innovation: np.ndarray | None = None
    innovation_cov: np.ndarray | None = None
    log_likelihood: float = 0.0

    @property
    def std(self) -> np.ndarray:
        """Standard deviation of every state ``(n,)``."""
        return np.sqrt(np.clip(np.diag(self.P), 0, None))


@dataclass
class FilterResult:
    """A filter's run over a record of ``m`` samples, ``n`` states and ``k`` outputs.

    Attributes:
        t: times ``(m,)`` (sample numbers for a discrete-time model).
        x, P: filtered mean ``(m, n)`` and covariance ``(m, n, n)`` (after ``y[i]``).
        x_predicted, P_predicted: the same before ``y[i]`` (one-step predictions; row 0 is
            the given ``x0``, ``P0``).
        innovations: ``y[i] - h(x_predicted[i])`` ``(m, k)`` (0 where ``y`` is missing).
        innovation_cov: their covariance ``(m, k, k)`` (identity rows where missing).
        log_likelihood: ``Σ log p(y_i | y_0 ... y_{i-1})`` (Gaussian, missing outputs skipped).
        cross: ``Cov(x_i, x_{i+1})`` of the filtered and next predicted state ``(m - 1, n, n)``
            (what the Rauch–Tung–Striebel smoother needs).
        measured: ``(m, k)`` bool, which outputs were present.
        state_names, output_names: labels.
        log_likelihood_terms: ``log p(y_i | y_0 ... y_{i-1})`` of every sample ``(m,)``.
    """

    t: np.ndarray
    x: np.ndarray
    P: np.ndarray
    x_predicted: np.ndarray
    P_predicted: np.ndarray
    innovations: np.ndarray
    innovation_cov: np.ndarray
    log_likelihood: float
    cross: np.ndarray
    measured: np.ndarray
    state_names: list
    output_names: list
    log_likelihood_terms: np.ndarray

    @property
    def std(self) -> np.ndarray:
        """Standard deviation of every filtered state ``(m, n)``."""
        return np.sqrt(np.clip(np.diagonal(self.P, axis1=1, axis2=2), 0, None))

    def normalised_innovations_squared(self) -> np.ndarray:
        """``eᵢᵀ Sᵢ⁻¹ eᵢ`` ``(m,)``: chi-squared with as many degrees of freedom as outputs
        measured at sample ``i`` when the filter's noise levels are right (its mean is the
        number of outputs: a consistency check)."""
        solved = np.linalg.solve(self.innovation_cov, self.innovations[..., None])[..., 0]
        return np.einsum("mk,mk->m", self.innovations, solved)

    def state(self, i: int = -1) -> FilterState:
        """The filtered belief at sample ``i`` as a :class:`FilterState` (to continue online)."""
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)) \
                or not -len(self.t) <= i < len(self.t):
            raise ParameterError(f"i must be a sample index in [{-len(self.t)}, {len(self.t)}); "
                                 f"got {i!r}")
        i = range(len(self.t))[i]
        return FilterState(self.x[i].copy(), self.P[i].copy(), self.innovations[i].copy(),
                           self.innovation_cov[i].copy(),
                           float(np.sum(self.log_likelihood_terms[:i + 1])))
