"""Uncertainty of every learned term by block bootstraps on Gram statistics.

The data are cut into contiguous blocks (long enough to keep the correlation that
smoothing and differentiation put into neighbouring samples) and each block's
``ΘᵀΘ``, ``Θᵀy`` and ``yᵀy`` are computed once. A resample is then a combination
of those p×p statistics followed by the model's own optimizer, so it costs a p×p
solve, not a pass over the data, and term selection is resampled too
(inclusion probabilities). A model whose terms were chosen by forecasts (the default
selection) keeps them in every resample (re-running the forecasts 200 times would cost
200 selections): its intervals are those of the chosen terms' coefficients, each included
with probability 1. Two schemes:

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

from ...constraints import (
    InstanceOf,
    Integral,
    Interval,
    Options,
    Real,
    check_argument,
    validate_params,
)
from ...errors import ConvergenceError, ParameterError
from ...optimizers import GramStatistics
from ...optimizers.resampling import from_blocks
from ...resources import check_memory, n_bytes
from ...selection.candidates import FoldFits
from .checks import model_data

BOOTSTRAP_CONSTRAINTS = {
    "n_resamples": [Interval(Integral, 2)], "method": [Options(("wild", "pairs"))],
    "seed": [None, Interval(Integral, 0), InstanceOf(np.random.Generator, "a numpy Generator")]}


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
        validate_params("interval", {"level": level},
                        {"level": [Interval(Real, 0, 1, closed="neither")]})
        q = (1 - level) / 2
        return np.quantile(self.samples, q, axis=0), np.quantile(self.samples, 1 - q, axis=0)

    def table(self, precision: int = 4, min_inclusion: float = 0.05) -> str:
        """Table of terms active in the estimate or in >= ``min_inclusion`` of resamples."""
        validate_params("table", {"precision": precision, "min_inclusion": min_inclusion},
                        {"precision": [Interval(Integral, 0, 17)],
                         "min_inclusion": [Interval(Real, 0, 1)]})
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

    @classmethod
    def from_ensemble(cls, model) -> CoefficientUncertainty:
        """The ensemble's models as samples: a model fitted with an
        :class:`~discrepancy.optimizers.EnsembleOptimizer` gets the bootstrap's table,
        intervals and ``model.print(uncertainty=...)`` (``block_length`` 1: samples were
        drawn one by one)."""
        model.check_is_fitted()
        samples = getattr(model.optimizer_, "coef_list_", None)
        if samples is None:
            raise ParameterError(f"from_ensemble needs a model fitted with an "
                                 f"EnsembleOptimizer; this one's is {model.optimizer_!r}")
        return cls(model.coef_.copy(), np.asarray(samples), list(model.state_names_),
                   model.get_feature_names(), 1)


def block_statistics(model, x, t=None, u=None, x_dot=None, *, block_length: int | None = None,
                     sample_weight=None):
    """Per-block Gram statistics of the fitted model's residuals: ``(blocks, folds, length)``.

    Blocks are contiguous and nest in the fit's cross-validation segments (their length
    divides the segment), so ``folds[b]`` is the fold of block ``b`` and a resample's fold
    statistics are sums of its blocks: the automatic threshold is chosen again, by the
    same cross-validation, in every resample.
    """
    setup = model.setup_
    segment = setup.fold_segment
    if block_length is not None and (not Interval(Integral, 2).is_satisfied_by(block_length)
                                     or segment % block_length):
        raise ParameterError(f"block_length must be an integer >= 2 that divides the fit's "
                             f"cross-validation segment ({segment} rows); got {block_length!r}")
    trajectories = model_data(model, x, t, u, x_dot, sample_weight)
    total = sum(tr.n_samples for tr in trajectories)
    length = block_length or _default_block(total, segment, setup.differentiation.halo or 0)
    p = setup.n_features
    check_memory(f"the bootstrap's statistics of about {total // length} blocks of {p} "
                 "columns", 3 * n_bytes((total // length + len(trajectories), p, p)),
                 "Use a longer block_length or a smaller library")
    n_folds = setup.new_statistics().n_folds
    blocks, folds, row = [], [], 0
    for tr in trajectories:
        z, y, xd = setup.rows(tr)
        row_weight = setup.row_weights(tr)
        start = 0
        while start < len(z):  # blocks on the grid of data rows, so they nest in segments
            stop = min(len(z), start + length - (row + start) % length)
            stats = GramStatistics(setup.n_features, setup.n_states)
            rows = slice(start, stop)
            weight = None if row_weight is None else row_weight[rows]
            blocks.append(stats.add(setup.transform(z[rows]), y[rows], xd[rows], weight))
            folds.append(((row + start) // segment) % n_folds)
            start = stop
        row += len(z)
    if len(blocks) < 10:
        raise ParameterError(f"only {len(blocks)} blocks of {length} samples; the bootstrap "
                             "needs at least 10 (use a smaller block_length or more data)")
    return blocks, np.array(folds), int(length)


def _default_block(total: int, segment: int, halo: int) -> int:
    """At least two derivative windows (shorter blocks cut the negative correlation lobes
    of differentiated noise and overstate the variance) when the data allow 20 blocks,
    never longer than the segment; a power of two, so it divides the segment."""
    want = max(2 * (2 * halo + 1), 16)
    fit = max(2, total // 20)
    length = min(want, fit, segment)
    return 1 << (length.bit_length() - 1)


def _wild(gram, rhs, yy, coef, rng):
    """Per-block resampled ``Θ_bᵀy*`` ``(B, p, n)`` and ``Σ y*²`` ``(B, n)``: block residuals
    flipped by random signs (fixed design)."""
    xi = coef.T                                              # (p, n)
    fitted = np.einsum("bpq,qn->bpn", gram, xi)              # Θ_bᵀ Θ_b ξ̂
    cross = rhs - fitted                                     # Θ_bᵀ e_b
    fit_sq = np.einsum("pn,bpn->bn", xi, fitted)             # |Θ_b ξ̂|²
    res_sq = yy - 2 * np.einsum("pn,bpn->bn", xi, rhs) + fit_sq  # |e_b|²
    mixed = np.einsum("pn,bpn->bn", xi, cross)               # ξ̂ᵀ Θ_bᵀ e_b
    s = rng.choice([-1.0, 1.0], size=len(gram))
    return fitted + s[:, None, None] * cross, fit_sq + res_sq + 2 * s[:, None] * mixed


def bootstrap(model, x, t=None, u=None, x_dot=None, *, n_resamples: int = 200,
              block_length: int | None = None, method: str = "wild", seed: int = 0,
              sample_weight=None) -> CoefficientUncertainty:
    """Bootstrap the coefficients of a fitted model on (its training) data; see module doc."""
    from tqdm.auto import tqdm

    model.check_is_fitted()
    validate_params("bootstrap", {"n_resamples": n_resamples, "method": method, "seed": seed},
                    BOOTSTRAP_CONSTRAINTS)
    check_memory(f"{n_resamples} resampled coefficient matrices {model.coef_.shape}",
                 n_bytes((n_resamples, *model.coef_.shape)), "Ask for fewer n_resamples")
    blocks, folds, length = block_statistics(model, x, t, u, x_dot, block_length=block_length,
                                             sample_weight=sample_weight)
    gram = np.stack([b.gram for b in blocks])
    rhs = np.stack([b.rhs for b in blocks])
    yy = np.stack([b.yy for b in blocks])
    signal = np.stack([b.signal for b in blocks])
    counts = np.array([b.count for b in blocks])
    template = model.setup_.new_statistics()
    rng = np.random.default_rng(seed)
    samples = np.empty((n_resamples, *model.coef_.shape))
    for r in tqdm(range(n_resamples), desc="bootstrap", disable=None, leave=False):
        if method == "wild":
            b, sq = _wild(gram, rhs, yy, model.coef_, rng)
            stats = from_blocks(gram, b, sq, signal, counts, folds, template)
        else:
            w = np.bincount(rng.integers(0, len(gram), len(gram)), minlength=len(gram))
            stats = from_blocks(gram * w[:, None, None], rhs * w[:, None, None],
                                yy * w[:, None], signal * w[:, None], counts * w, folds,
                                template)
        samples[r] = _resample_fit(model, stats)
    return CoefficientUncertainty(model.coef_.copy(), samples, list(model.state_names_),
                                  model.get_feature_names(), length)


def _resample_fit(model, stats) -> np.ndarray:
    """Coefficients of one resample: the model's optimizer, or its forecast-chosen terms
    refitted (least squares, the optimizer's constraints)."""
    if getattr(model, "forecast_selection_", None) is None:
        opt = copy.deepcopy(model.optimizer_)
        opt.fit_statistics(stats)
        return opt.coef_
    constraints = getattr(model.setup_.optimizer, "constraints", None)
    return FoldFits(stats, constraints, 0.0).coefficients(model.coef_ != 0, None)


def check_uncertainty(model, uncertainty) -> None:
    """ParameterError unless ``uncertainty`` is ``model``'s own bootstrap result."""
    if not isinstance(uncertainty, CoefficientUncertainty) or \
            uncertainty.samples.shape[1:] != model.coef_.shape or \
            list(uncertainty.feature_names) != model.get_feature_names() or \
            not np.array_equal(uncertainty.estimate, model.coef_):
        raise ParameterError("uncertainty must be this model's bootstrap(...) result "
                             f"(coefficients {model.coef_.shape}); got "
                             f"{type(uncertainty).__name__}")


def quantiles(curves: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Pointwise ``level`` band ``(low, high)`` of resampled curves ``(R, ...)``, ignoring
    resamples that are NaN (diverged)."""
    check_argument("level", level, Interval(Real, 0, 1, closed="neither"))
    tail = (1 - level) / 2
    low, high = np.nanquantile(curves, [tail, 1 - tail], axis=0)
    return low, high


def predict_interval(model, x, u, uncertainty, level):
    """See :meth:`DiscrepancyModel.predict_interval`."""
    check_uncertainty(model, uncertainty)
    x, u = model._variables(x, u)
    check_memory(f"the {len(uncertainty.samples)} resampled predictions of {len(x)} samples",
                 n_bytes((len(uncertainty.samples), *x.shape)) + n_bytes((len(x),
                                                                        model.coef_.shape[1])),
                 "Predict fewer samples at a time")
    theta = model.feature_library_.transform(x if u is None else np.hstack([x, u]))
    prior = model.prior_(x, u)
    curves = prior[None] + np.einsum("mp,rnp->rmn", theta, uncertainty.samples)
    return quantiles(curves, level)


def simulate_interval(model, x0, t, u, uncertainty, level, n_draws, seed, **integrator_kws):
    """See :meth:`DiscrepancyModel.simulate_interval`."""
    import warnings

    from tqdm.auto import tqdm


    check_uncertainty(model, uncertainty)
    validate_params("simulate_interval", {"seed": seed}, {"seed": BOOTSTRAP_CONSTRAINTS["seed"]})
    samples = uncertainty.samples
    if n_draws is not None:
        check_argument("n_draws", n_draws, None, Interval(Integral, 2))
        pick = np.random.default_rng(seed).choice(len(samples), min(n_draws, len(samples)),
                                                  replace=False)
        samples = samples[pick]
    runs, failed = [], 0
    for coef in tqdm(samples, desc="simulate", disable=None, leave=False):
        try:
            runs.append(model.with_coefficients(coef).simulate(x0, t, u=u, **integrator_kws))
        except ConvergenceError:
            failed += 1
            runs.append(np.full((len(np.atleast_1d(t)), model.n_states_), np.nan))
    if failed:
        warnings.warn(f"{failed} of {len(samples)} resampled models diverged; the band is "
                      "taken over the others", stacklevel=3)
    return quantiles(np.array(runs), level)
