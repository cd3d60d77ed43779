"""Figure of the bootstrap distribution of each learned term."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np


def uncertainty_figure(unc, *, truth: dict | None = None, min_inclusion: float = 0.05,
                       max_terms: int = 12, title: str = ""):
    """One histogram per term (own scale): bootstrap samples, estimate, 95 % interval, truth.

    Args:
        unc: a :class:`~discrepancy.models.core.uncertainty.CoefficientUncertainty`.
        truth: optional ``{(state, term): value}`` drawn as a black line.
        min_inclusion: also show inactive terms selected in at least this fraction of resamples.
        max_terms: at most this many panels (active terms first).
    """
    if not hasattr(unc, "interval") or not hasattr(unc, "inclusion_probability"):
        from ..errors import ParameterError, describe
        raise ParameterError(f"unc must be a model's bootstrap() result; got {describe(unc)}")
    low, high = unc.interval()
    inc = unc.inclusion_probability
    rows = [(i, j) for i in range(len(unc.state_names)) for j in range(len(unc.feature_names))
            if unc.estimate[i, j] != 0 or inc[i, j] >= min_inclusion]
    rows = sorted(rows, key=lambda ij: unc.estimate[ij] == 0)[:max_terms]
    cols = min(3, max(len(rows), 1))
    n_rows = int(np.ceil(len(rows) / cols)) or 1
    fig, axes = plt.subplots(n_rows, cols, figsize=(3.6 * cols, 2.4 * n_rows), squeeze=False)
    for ax, (i, j) in zip(axes.flat, rows, strict=False):
        state, term = unc.state_names[i], unc.feature_names[j]
        ax.hist(unc.samples[:, i, j], bins=30, color="tab:blue", alpha=0.6)
        ax.axvspan(low[i, j], high[i, j], color="tab:blue", alpha=0.12)
        ax.axvline(unc.estimate[i, j], color="tab:blue", lw=1.5, label="estimate")
        if truth and (state, term) in truth:
            ax.axvline(truth[(state, term)], color="k", lw=1.5, ls="--", label="truth")
        ax.set_title(f"({state})': {term}   selected {100 * inc[i, j]:.0f} %", fontsize=9)
        ax.tick_params(labelsize=8)
        ax.ticklabel_format(axis="x", useOffset=False)
    for ax in list(axes.flat)[len(rows):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle(title or f"block bootstrap, {unc.samples.shape[0]} resamples "
                 "(shaded: 95 % interval)")
    fig.tight_layout()
    return fig
