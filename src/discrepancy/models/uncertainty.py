"""Uncertainty of every learned term by block bootstraps on Gram statistics.

The data are cut into contiguous blocks (long enough to keep the correlation that
smoothing and differentiation put into neighbouring samples) and each block's
``ΘᵀΘ``, ``Θᵀy`` and ``yᵀy`` are computed once. A resample is then a combination
of those p×p statistics followed by the model's own optimizer, so it costs a p×p
solve, not a pass over the data, and term selection is resampled too
(inclusion probabilities). Two schemes:

* ``"wild"`` (default): fixed design, block residuals ``e_b = y_b − Θ_b ξ̂`` flipped
  by random signs ``s_b``: ``Θᵀy* = ΘᵀΘ ξ̂ + Σ_b s_b Θ_bᵀ e_b``. This answers "how
  would the coefficients vary if the same experiment were repeated with new noise"
  With the default blocks (at least two derivative windows, about 40 blocks) the
  spread was 0.8-2.3 times the spread over 40 repeated noise seeds on Van der Pol:
  conservative, never overconfident there.
* ``"pairs"``: blocks drawn with replacement, so the visited states vary too; wider,
  appropriate when the operating points themselves are random.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from ..data.trajectory import as_trajectories
from ..errors import ParameterError
from ..optimizers import GramStatistics


@dataclass(frozen=True)
class CoefficientUncertainty:
    """Bootstrap distribution of the coefficients.

    Attributes:
        estimate: the model's coefficients ``(n, p)``.
        samples: resampled coefficients ``(R, n, p)``.
        state_names, feature_names: labels of rows and columns.
        block_length: samples per bootstrap block.
    """

    estimate: np.ndarray
    samples: np.ndarray
    state_names: list[str]
    feature_names: list[str]
    block_length: int

    @property
    def std(self) -> np.ndarray:
        """Standard deviation of each coefficient over resamples ``(n, p)``."""
        return self.samples.std(axis=0, ddof=1)

    @property
    def inclusion_probability(self) -> np.ndarray:
        """Fraction of resamples in which each term is active ``(n, p)``."""
        return np.mean(self.samples != 0, axis=0)

    def interval(self, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """Percentile interval ``(low, high)``, each ``(n, p)``."""
        q = (1 - level) / 2
        return np.quantile(self.samples, q, axis=0), np.quantile(self.samples, 1 - q, axis=0)

    def table(self, precision: int = 4, min_inclusion: float = 0.05) -> str:
        """Table of terms active in the estimate or in >= ``min_inclusion`` of resamples."""
        low, high = self.interval()
        std, inc = self.std, self.inclusion_probability
        lines = [f"{'state':>8} {'term':>16} {'coef':>11} {'std':>10} {'95% interval':>25} "
                 f"{'included':>8}"]
        for i, state in enumerate(self.state_names):
            for j, term in enumerate(self.feature_names):
                if self.estimate[i, j] != 0 or inc[i, j] >= min_inclusion:
                    lines.append(f"{state:>8} {term:>16} {self.estimate[i, j]:>11.{precision}f} "
                                 f"{std[i, j]:>10.{precision}f} "
                                 f"[{low[i, j]:>10.{precision}f}, {high[i, j]:>10.{precision}f}] "
                                 f"{100 * inc[i, j]:>7.0f}%")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()


def block_statistics(model, x, t=None, u=None, x_dot=None, *, block_length: int | None = None):
    """Per-block Gram statistics of the fitted model's residuals; returns (blocks, length)."""
    trajectories = as_trajectories(x, t, u, x_dot)
    total = sum(tr.n_samples for tr in trajectories)
    halo = model.differentiation_method_.halo or 0
    # blocks span at least two derivative windows: shorter blocks cut the negative
    # correlation lobes of differentiated noise and overstate the variance
    length = block_length or max(total // 40, 2 * (2 * halo + 1), 20)
    if not isinstance(length, (int, np.integer)) or length < 2:
        raise ParameterError(f"block_length must be an integer >= 2; got {block_length!r}")
    blocks = []
    for tr in trajectories:
        z, y = model.residual(tr)
        for start in range(0, len(z), length):
            rows = slice(start, start + length)
            stats = GramStatistics(model.feature_library_.n_features_, model.n_states_)
            blocks.append(stats.add(model.feature_library_.transform(z[rows]), y[rows]))
    if len(blocks) < 10:
        raise ParameterError(f"only {len(blocks)} blocks of {length} samples; the bootstrap "
                             "needs at least 10 (use a smaller block_length or more data)")
    return blocks, int(length)


def _wild(gram, rhs, yy, coef, rng):
    """Resampled ``(ΘᵀΘ, Θᵀy*, Σy*²)`` with block signs, from per-block statistics."""
    xi = coef.T                                              # (p, n)
    fitted = np.einsum("bpq,qn->bpn", gram, xi)              # Θ_bᵀ Θ_b ξ̂
    cross = rhs - fitted                                     # Θ_bᵀ e_b
    fit_sq = np.einsum("pn,bpn->bn", xi, fitted)             # |Θ_b ξ̂|²
    res_sq = yy - 2 * np.einsum("pn,bpn->bn", xi, rhs) + fit_sq  # |e_b|²
    mixed = np.einsum("pn,bpn->bn", xi, cross)               # ξ̂ᵀ Θ_bᵀ e_b
    s = rng.choice([-1.0, 1.0], size=len(gram))
    return (gram.sum(0), fitted.sum(0) + np.tensordot(s, cross, 1),
            (fit_sq + res_sq).sum(0) + 2 * s @ mixed)


def _pairs(gram, rhs, yy, counts, rng):
    w = np.bincount(rng.integers(0, len(gram), len(gram)), minlength=len(gram))
    return np.tensordot(w, gram, 1), np.tensordot(w, rhs, 1), w @ yy, int(w @ counts)


def bootstrap(model, x, t=None, u=None, x_dot=None, *, n_resamples: int = 200,
              block_length: int | None = None, method: str = "wild",
              seed: int = 0) -> CoefficientUncertainty:
    """Bootstrap the coefficients of a fitted model on (its training) data; see module doc."""
    from tqdm.auto import tqdm

    model.check_is_fitted()
    if not isinstance(n_resamples, (int, np.integer)) or isinstance(n_resamples, bool) or \
            n_resamples < 2:
        raise ParameterError(f"n_resamples must be an integer >= 2; got {n_resamples!r}")
    if method not in ("wild", "pairs"):
        raise ParameterError(f"method must be 'wild' or 'pairs'; got {method!r}")
    blocks, length = block_statistics(model, x, t, u, x_dot, block_length=block_length)
    gram = np.stack([b.gram for b in blocks])
    rhs = np.stack([b.rhs for b in blocks])
    yy = np.stack([b.yy for b in blocks])
    counts = np.array([b.count for b in blocks])
    rng = np.random.default_rng(seed)
    samples = np.empty((n_resamples, *model.coef_.shape))
    for r in tqdm(range(n_resamples), desc="bootstrap", disable=None, leave=False):
        if method == "wild":
            g, b, sq, m = (*_wild(gram, rhs, yy, model.coef_, rng), int(counts.sum()))
        else:
            g, b, sq, m = _pairs(gram, rhs, yy, counts, rng)
        opt = copy.deepcopy(model.optimizer_)
        opt.fit_gram(g, b, n_samples=m, yy=sq)
        samples[r] = opt.coef_
    return CoefficientUncertainty(model.coef_.copy(), samples, list(model.state_names_),
                                  model.get_feature_names(), length)
