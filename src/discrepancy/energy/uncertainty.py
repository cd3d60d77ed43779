"""Uncertainty of a learned dissipation law: a wild block bootstrap of the energy fit.

The residual ``r(t) = dH(t) - model(t)`` of the fitted cumulative curve is cut into blocks of
``block_seconds``; a resample flips each block's residual by a random sign,
``dH* = model + s_b r``, and refits the selected terms with the same non-negative fit. This
answers "how would the coefficients vary if the swing were recorded again with new noise"
while keeping the residual's correlation within a block (smoothing, quantisation) and its
changing size along the decay. The terms are not re-selected: the intervals are those of the
chosen law. Written here because the model's Gram-based bootstrap assumes an unconstrained
linear fit of pointwise residuals, not a non-negative fit of a cumulative curve.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..constraints import validate_params
from ..data.validation import check_array
from ..errors import ParameterError
from ..models.core.uncertainty import BOOTSTRAP_CONSTRAINTS, CoefficientUncertainty
from .regression import block_weights, nonnegative_fit


@dataclass(frozen=True)
class DissipationUncertainty(CoefficientUncertainty):
    """Bootstrap distribution of a dissipation law's coefficients and of its offset.

    Attributes (besides :class:`~discrepancy.models.core.uncertainty.CoefficientUncertainty`'s):
        offsets: each resample's offset ``c`` (J), ``(R,)``: with it a resample reproduces
            its own fit of the training curve, so a forecast that continues the training fit
            carries the uncertainty of where that fit hands over.
    """

    offsets: np.ndarray

    def curves(self, features: np.ndarray, *, continued: bool) -> np.ndarray:
        """Every resample's model ``dH`` (J), ``(R, m)``, from the terms' integrated powers
        ``features`` ``(m, k)``; ``continued``: with each resample's offset (the training
        fit continued), else starting at 0 (a new trajectory)."""
        features = check_array("features", features, n_cols=self.samples.shape[2])
        start = self.offsets[:, None] if continued else 0.0
        return start + self.samples[:, 0, :] @ features.T


def quantile_band(curves: np.ndarray, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Pointwise ``level`` band ``(low, high)``, each ``(m,)``, of resampled curves ``(R, m)``."""
    if not 0 < level < 1:
        raise ParameterError(f"level must be in (0, 1); got {level!r}")
    tail = (1 - level) / 2
    low, high = np.quantile(curves, [tail, 1 - tail], axis=0)
    return low, high


def bootstrap_dissipation(features: np.ndarray, delta_h: np.ndarray, coef: np.ndarray,
                          offset: float, names: list[str], *, samples_per_block: int,
                          fit_block: int | None = None, n_resamples: int = 200,
                          seed: int = 0, limits=None
                          ) -> DissipationUncertainty:
    """Bootstrap the coefficients ``coef`` ``(k,)`` of ``delta_h ~ offset + features @ coef``.

    ``features`` ``(m, k)`` are the selected terms' integrated powers, ``fit_block`` the fit's
    own block length (``None``: cumulative fit), ``samples_per_block`` the bootstrap block,
    ``limits`` the fit's soundness constraints on these terms
    (:class:`~discrepancy.energy.soundness.Limits`), kept by every resample.
    """
    from tqdm.auto import tqdm

    m = len(delta_h)
    validate_params("bootstrap", {"n_resamples": n_resamples, "seed": seed},
                    {k: BOOTSTRAP_CONSTRAINTS[k] for k in ("n_resamples", "seed")})
    if not 2 <= samples_per_block <= m // 4:
        raise ParameterError(f"bootstrap blocks must hold 2 to {m // 4} samples (at least 4 "
                             f"blocks); got {samples_per_block}")
    model = offset + features @ coef
    residual = delta_h - model
    n_blocks = -(-m // samples_per_block)
    # the block fit's weights stay those of the original fit (fixed design): reweighting each
    # resample by its own noisy losses made the estimator nonlinear and the intervals biased
    weights = None if fit_block is None else block_weights(delta_h, fit_block)
    rng = np.random.default_rng(seed)
    samples = np.empty((n_resamples, 1, len(coef)))
    offsets = np.empty(n_resamples)
    for r in tqdm(range(n_resamples), desc="bootstrap", disable=None, leave=False):
        signs = np.repeat(rng.choice([-1.0, 1.0], n_blocks), samples_per_block)[:m]
        fitted = nonnegative_fit(features, model + signs * residual, fit_block, weights,
                                 limits)
        offsets[r], samples[r, 0] = fitted[0], fitted[1:]
    return DissipationUncertainty(np.asarray(coef, float)[None, :].copy(), samples, ["dH"],
                                  list(names), samples_per_block, offsets)
