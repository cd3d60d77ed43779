"""Figures of automatic choices: the threshold path, forecast selection, procedures."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np


def selection_figure(model, *, title: str = ""):
    """One panel per equation: the held-out error of every support on the STLSQ threshold
    path against its number of terms, one standard error as bars, the chosen support ringed.

    Args:
        model: a DiscrepancyModel fitted with ``STLSQ(threshold="auto")``.
    """
    model.check_is_fitted()
    paths = getattr(model.optimizer_, "selection_", None)
    if paths is None:
        from ..errors import ParameterError
        raise ParameterError("the model's optimizer chose no threshold (give it "
                             "STLSQ(threshold='auto')); there is no path to draw")
    fig, axes = plt.subplots(1, len(paths), figsize=(3.6 * len(paths), 3.2), squeeze=False)
    for ax, name, path in zip(axes[0], model.state_names_, paths, strict=True):
        terms, error = np.array(path["n_terms"]), np.array(path["error"])
        se = np.array(path["error_se"])
        ax.errorbar(terms, error, yerr=se, fmt="o-", ms=3, lw=1, capsize=2)
        k = path["chosen"]
        ax.plot(terms[k], error[k], "o", ms=11, mfc="none", mec="tab:red", mew=1.5,
                label=f"chosen: {terms[k]} terms")
        if path["criterion"] != "BIC" and np.all(error > 0):
            ax.set_yscale("log")
        ax.set_xlabel("terms in the equation")
        ax.set_ylabel("held-out mean square error" if path["criterion"] != "BIC" else "BIC")
        ax.set_title(f"({name})'", fontsize=9)
        ax.legend(fontsize=8)
    fig.suptitle(title or f"threshold path scored by {paths[0]['criterion']}", fontsize=10)
    fig.tight_layout()
    return fig


def forecast_selection_figure(model, *, title: str = ""):
    """How forecasts chose the model's terms: left, every candidate's held-out forecast
    error against its number of terms (one standard error as bars; the prior alone
    squared, the equation-error choice a triangle, the chosen ringed); right, the RMS
    scaled error at each lead of the prior alone and of the chosen model.

    Args:
        model: a DiscrepancyModel fitted with forecast selection (``forecast_selection_``).
    """
    model.check_is_fitted()
    sel = getattr(model, "forecast_selection_", None)
    if sel is None:
        from ..errors import ParameterError
        raise ParameterError("the model was not chosen by forecasts (forecast_selection_ is "
                             "None): fit it with the default selection")
    fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.4))
    terms, score, se = np.array(sel.n_terms), np.array(sel.score), np.array(sel.score_se)
    left.errorbar(terms, score, yerr=se, fmt="o", ms=4, color="0.45", capsize=2,
                  label="candidates")
    for label, marker in (("prior alone", "s"), ("equation error", "^")):
        if label in sel.labels:
            k = sel.labels.index(label)
            left.plot(terms[k], score[k], marker, ms=8, color="tab:blue" if marker == "s"
                      else "tab:orange", label=label)
    k = sel.chosen
    left.plot(terms[k], score[k], "o", ms=13, mfc="none", mec="tab:red", mew=1.5,
              label=f"chosen: {terms[k]} terms")
    left.set_yscale("log")
    left.set_xlabel("terms in the model")
    left.set_ylabel("held-out forecast error (scaled MSE)")
    left.legend(fontsize=7)
    leads = np.arange(len(sel.lead_rms["chosen"])) * sel.horizon / max(
        len(sel.lead_rms["chosen"]) - 1, 1)
    for name, curve in sel.lead_rms.items():
        right.plot(leads, curve, label=name)
    right.set_xlabel("lead (samples)")
    right.set_ylabel("RMS scaled error")
    right.legend(fontsize=7)
    fig.suptitle(title or f"selection by forecasts: {sel.n_windows} origins, horizon "
                 f"{sel.horizon_time:.3g}", fontsize=10)
    fig.tight_layout()
    return fig


def procedure_figure(choice, *, title: str = ""):
    """Every candidate of :func:`discrepancy.choose_procedure`: its forecast error at each
    origin (dots) and their mean with one standard error (bar), the chosen ringed and the
    prior alone's mean as a dashed line; a candidate whose forecasts diverged at some
    origins (no dot, no mean) says at how many, in red at the top."""
    if not hasattr(choice, "scores") or not hasattr(choice, "chosen"):
        from ..errors import ParameterError, describe
        raise ParameterError(f"choice must be what choose_procedure returns; got "
                             f"{describe(choice)}")
    names = list(choice.scores)
    fig, ax = plt.subplots(figsize=(max(5.0, 0.9 * len(names) + 2), 3.6))
    for i, name in enumerate(names):
        row = choice.scores[name]
        errors = np.array(row["forecast_errors"], dtype=float)
        ax.plot(np.full(len(errors), i), errors, ".", color="0.6")
        ax.errorbar(i, row["mean"], yerr=row["se"], fmt="o", color="tab:blue", capsize=3)
        if name == choice.chosen:
            ax.plot(i, row["mean"], "o", ms=14, mfc="none", mec="tab:red", mew=1.5)
        diverged = int(np.sum(~np.isfinite(errors)))
        if diverged:
            ax.text(i, 0.97, f"diverged at\n{diverged} of {errors.size}", ha="center", va="top",
                    transform=ax.get_xaxis_transform(), fontsize=7, color="tab:red")
    if "prior alone" in choice.scores:
        ax.axhline(choice.scores["prior alone"]["mean"], ls="--", color="0.3", lw=1,
                   label="prior alone")
        ax.legend(fontsize=8)
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels([f"{n}\n({choice.scores[n]['n_terms']} terms)" for n in names],
                       rotation=30, ha="right", fontsize=7)
    ax.set_yscale("log")
    ax.set_ylabel("forecast error (scaled MSE)")
    ax.set_title(title or f"candidates scored by forecasts; chosen: {choice.chosen}",
                 fontsize=10)
    fig.tight_layout()
    return fig
