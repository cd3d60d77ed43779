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

import numpy as np

from ..errors import ParameterError
from ..models.uncertainty import CoefficientUncertainty
from .dissipation import block_weights, nonnegative_fit


def bootstrap_dissipation(features: np.ndarray, delta_h: np.ndarray, coef: np.ndarray,
                          offset: float, names: list[str], *, samples_per_block: int,
                          fit_block: int | None = None, n_resamples: int = 200,
                          seed: int = 0) -> CoefficientUncertainty:
    """Bootstrap the coefficients ``coef`` ``(k,)`` of ``delta_h ~ offset + features @ coef``.

    ``features`` ``(m, k)`` are the selected terms' integrated powers, ``fit_block`` the fit's
    own block length (``None``: cumulative fit), ``samples_per_block`` the bootstrap block.
    """
    from tqdm.auto import tqdm

    m = len(delta_h)
    if not isinstance(n_resamples, (int, np.integer)) or n_resamples < 2:
        raise ParameterError(f"n_resamples must be an integer >= 2; got {n_resamples!r}")
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
    for r in tqdm(range(n_resamples), desc="bootstrap", disable=None, leave=False):
        signs = np.repeat(rng.choice([-1.0, 1.0], n_blocks), samples_per_block)[:m]
        samples[r, 0] = nonnegative_fit(features, model + signs * residual, fit_block,
                                         weights)[1:]
    return CoefficientUncertainty(np.asarray(coef, float)[None, :].copy(), samples, ["dH"],
                                  list(names), samples_per_block)
