"""Figures of measured data, discrepancies and validation runs (like the paper's Fig. 2)."""
from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np

from ..data.validation import as_float_array
from ..errors import ParameterError, ShapeError, describe


def _table(name: str, a, m: int, n: int) -> np.ndarray:
    """``a`` as an ``(m, n)`` float array (non-finite values allowed: a diverged run plots)."""
    arr = as_float_array(name, a)
    if arr.shape != (m, n):
        raise ShapeError(f"{name} must be ({m}, {n}) (samples, states); got shape {arr.shape}")
    return arr


COLORS = {"true": "k", "measured": "0.55", "prior": "tab:red", "hybrid": "tab:blue"}


def discrepancy_figure(t, x_measured, residual, learned, state_names, *, title=""):
    """Measured states (left) and, per state, the discrepancy from data vs the learned g (right).

    Args:
        t: times ``(m,)``; x_measured: ``(m, n)``; residual: ``ẋ − f_m`` from data ``(m, n)``;
        learned: ``g(x)`` of the fitted model ``(m, n)``.
    """
    n = len(state_names)
    t = as_float_array("t", t).reshape(-1)
    x_measured, residual, learned = (
        _table(name, a, len(t), n) for name, a in
        (("x_measured", x_measured), ("residual", residual), ("learned", learned)))
    fig, axes = plt.subplots(n, 2, figsize=(11, 2.6 * n), squeeze=False, sharex=True)
    for i, name in enumerate(state_names):
        axes[i, 0].plot(t, x_measured[:, i], color=COLORS["measured"], lw=0.8)
        axes[i, 0].set_ylabel(name)
        axes[i, 1].plot(t, residual[:, i], color=COLORS["measured"], lw=0.8,
                        label="ẋ − f_m (from data)")
        axes[i, 1].plot(t, learned[:, i], color=COLORS["hybrid"], lw=1.2, ls="--",
                        label="learned g(x)")
        axes[i, 1].set_ylabel(f"δ({name})'")
    axes[0, 0].set_title("measured states (noisy)")
    axes[0, 1].set_title("discrepancy")
    axes[0, 1].legend(loc="upper right", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def validation_figure(t, runs: dict[str, np.ndarray], state_names, *, title=""):
    """Phase portrait and time series of runs ``{"true": x, "prior": x, "hybrid": x}``."""
    n = len(state_names)
    if not isinstance(runs, Mapping) or not runs:
        raise ParameterError(f"runs must be a non-empty mapping of labels to states (m, n); "
                             f"got {describe(runs)}")
    t = as_float_array("t", t).reshape(-1)
    runs = {label: _table(f"runs[{label!r}]", x, len(t), n) for label, x in runs.items()}
    fig, axes = plt.subplots(1, 1 + n, figsize=(4.2 * (1 + n), 3.6))
    styles = {"true": dict(lw=2.2, alpha=0.5), "prior": dict(lw=1, ls=":"),
              "hybrid": dict(lw=1.2, ls="--")}
    for label, x in runs.items():
        kw = dict(color=COLORS.get(label), label=label, **styles.get(label, {}))
        if n >= 2:
            axes[0].plot(x[:, 0], x[:, 1], **kw)
        for i in range(n):
            axes[1 + i].plot(t, x[:, i], **kw)
    if n >= 2:
        axes[0].set_xlabel(state_names[0])
        axes[0].set_ylabel(state_names[1])
        axes[0].set_title("phase portrait")
    for i, name in enumerate(state_names):
        axes[1 + i].set_xlabel("t")
        axes[1 + i].set_ylabel(name)
    axes[-1].legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def coefficient_spread_figure(estimates: dict[str, np.ndarray], truth: dict[str, float], *,
                              title=""):
    """Relative error of each true term's coefficient over seeds, one strip per library.

    Args:
        estimates: ``{library label: array (seeds, terms)}`` of identified coefficients,
            columns in the order of ``truth``.
        truth: ``{term name: true coefficient}``.
    """
    terms = list(truth)
    fig, ax = plt.subplots(figsize=(2.2 + 1.6 * len(terms) * len(estimates), 3.4))
    ticks, labels = [], []
    for k, (label, est) in enumerate(estimates.items()):
        for j, term in enumerate(terms):
            pos = j * (len(estimates) + 1) + k
            rel = 100 * (est[:, j] - truth[term]) / abs(truth[term])
            ax.plot(np.full(len(rel), pos) + np.linspace(-0.15, 0.15, len(rel)), rel, "o",
                    ms=4, alpha=0.7, label=label if j == 0 else None, color=f"C{k}")
            ticks.append(pos)
            labels.append(term)
    ax.axhline(0, color="k", lw=0.8)
    for lim in (-1, 1):
        ax.axhline(lim, color="tab:red", lw=0.8, ls=":")
    ax.set_xticks(ticks, labels)
    ax.set_ylabel("coefficient error (% of true)")
    ax.legend(fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    return fig
