"""Figures of the energy discrepancy (like the paper's Figs. 4 and 5) and of friction laws."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from discrepancy.symbolic import compile_numpy


def energy_figure(t, e0, h_m, delta_h, *, split: float | None = None, title: str = ""):
    """Left: ``E0`` and ``H_m(t)`` (J); right: ``dH = E0 - H_m`` (J) (paper Fig. 4a)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.4))
    axes[0].plot(t, np.full_like(t, e0), "k--", lw=1, label="E0")
    axes[0].plot(t, h_m, color="tab:blue", lw=0.7, label="H_m = T + V")
    axes[1].plot(t, delta_h, color="tab:red", lw=0.8, label="dH = E0 - H_m")
    for ax, ylabel in zip(axes, ("energy (J)", "dissipated energy (J)"), strict=True):
        ax.set_xlabel("t (s)")
        ax.set_ylabel(ylabel)
        if split is not None:
            ax.axvline(split, color="0.5", ls=":", lw=1, label="validation starts")
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def fit_figure(panels, *, title: str = ""):
    """One column per panel: ``dH`` and the model (top), percentage error (bottom).

    Args:
        panels: list of dicts with ``t``, ``delta_h``, ``model`` (J), ``error`` (%),
            ``label`` (e.g. "training") and ``error_label`` (the normaliser); optionally
            ``error_band`` ``(low, high)`` (%), the errors a model's uncertainty allows
            (shaded; where it holds 0 the measured dH is inside the model's band) and
            ``band_label`` naming it (default: the 95 % bootstrap band).
    """
    fig, axes = plt.subplots(2, len(panels), figsize=(5.5 * len(panels), 5.6), squeeze=False)
    for j, p in enumerate(panels):
        axes[0, j].plot(p["t"], p["delta_h"], color="0.4", lw=1.6, label="dH (measured)")
        axes[0, j].plot(p["t"], p["model"], color="tab:blue", lw=1, ls="--", label="model")
        axes[0, j].set_title(p["label"])
        axes[0, j].set_ylabel("dH (J)")
        axes[0, j].legend(fontsize=8)
        if "error_band" in p:
            axes[1, j].fill_between(p["t"], *p["error_band"], color="tab:red", alpha=0.15,
                                    lw=0, label=p.get("band_label",
                                                      "95 % band of the model (bootstrap)"))
            axes[1, j].legend(fontsize=8)
        axes[1, j].plot(p["t"], p["error"], color="tab:red", lw=0.7)
        axes[1, j].set_ylabel(p.get("error_label", "error (%)"))
        axes[1, j].set_xlabel("t (s)")
        axes[1, j].axhline(0, color="k", lw=0.5)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def friction_law_figure(laws, *, speed_max: float = 10.0, title: str = ""):
    """Friction torque against joint speed for each law, joint 1 and joint 2.

    Args:
        laws: dict label -> list of ``(FrictionTerm, coefficient)``; the torque of a term is its
            power divided by the joint speed, evaluated with the other speed at rest. Terms
            that are not functions of the joint speeds alone (e.g. a mount's loss) are left
            out of this figure.
    """
    speeds = {"dphi1", "dphi2"}
    laws = {label: [(term, c) for term, c in terms if term.functions is None
                    and {s.name for s in term.power.free_symbols} <= speeds]
            for label, terms in laws.items()}
    w = np.linspace(-speed_max, speed_max, 801)
    w = w[w != 0]
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6))
    for j, (ax, name) in enumerate(zip(axes, ("joint 1 and arm 1 drag (dphi1 = w, dphi2 = 0)",
                                              "joint 2 and arm 2 drag (dphi1 = 0, dphi2 = -w)"),
                                       strict=True)):
        v = np.zeros((len(w), 2))
        v[:, 0] = w if j == 0 else 0.0
        v[:, 1] = 0.0 if j == 0 else -w   # joint 2 turns at dphi1 - dphi2 = w
        other = ("joint 2", "dphi2") if j == 0 else ("joint 1", "dphi1")
        shown = []
        for label, terms in laws.items():
            # each panel shows its own joint's and arm's laws (terms named after neither: both)
            power = sum((c * compile_numpy(term.power, ["dphi1", "dphi2"])(v)
                         for term, c in terms if not term.name.endswith(other)),
                        np.zeros(len(w)))
            ax.plot(w, power / w, lw=1.2, label=label)
            shown.append(power / w)
        # a narrow Stribeck peak near w = 0 would flatten everything else: clip to the bulk
        bulk = np.percentile(np.abs(np.concatenate(shown)), 95)
        if bulk > 0:
            ax.set_ylim(-1.4 * bulk, 1.4 * bulk)
        ax.set_xlabel("joint speed w (rad/s)")
        ax.set_ylabel("friction torque (N m)")
        ax.set_title(name)
        ax.axhline(0, color="k", lw=0.5)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def seeds_figure(seeds, k1_error, k2_error, val_error, *, title: str = ""):
    """Per seed: relative errors of k1, k2 (%) and validation error (% of max|dH|)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.4))
    x = np.arange(len(seeds))
    axes[0].bar(x - 0.2, k1_error, 0.4, label="k1 error (%)")
    axes[0].bar(x + 0.2, k2_error, 0.4, label="k2 error (%)")
    axes[1].bar(x, val_error, 0.6, color="tab:red", label="validation max error (% of max|dH|)")
    axes[0].axhline(1.0, color="tab:blue", ls=":", lw=1, label="1 % (k1 bar)")
    for ax in axes:
        ax.set_xticks(x, [str(s) for s in seeds])
        ax.set_xlabel("seed")
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def forecast_figure(table, *, marked=(), bar: float | None = None, title: str = ""):
    """Each procedure's largest forecast error from the origins inside training (x) against
    its validation error (y), both in % of the window's dH range, one colour per library
    (the text before the first comma of a procedure's name); ``marked`` procedures ringed.

    Args:
        table: ``{procedure: {"forecast_worst_percent_of_range": float,
            "validation_continued_percent_of_range": float}}``.
    """
    fig, ax = plt.subplots(figsize=(7, 4.6))
    libraries = list(dict.fromkeys(name.split(",")[0] for name in table))
    for i, library in enumerate(libraries):
        rows = [r for n, r in table.items() if n.split(",")[0] == library]
        ax.plot([r["forecast_worst_percent_of_range"] for r in rows],
                [r["validation_continued_percent_of_range"] for r in rows], "o",
                color=f"C{i}", ms=5, alpha=0.8, label=library)
    for name, label in marked:
        r = table[name]
        ax.plot(r["forecast_worst_percent_of_range"], r["validation_continued_percent_of_range"],
                "o", ms=13, mfc="none", mec="k", mew=1.2)
        ax.annotate(label, (r["forecast_worst_percent_of_range"],
                            r["validation_continued_percent_of_range"]),
                    textcoords="offset points", xytext=(8, 6), fontsize=8)
    if bar is not None:
        ax.axhline(bar, color="k", ls=":", lw=1, label=f"{bar:g} % (target)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("largest forecast error from origins inside training (% of range)")
    ax.set_ylabel("validation error, continued (% of range)")
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def dissipation_rate_figure(centres, measured, models, *, title: str = ""):
    """Mean dissipated power per block (W) against time: measured (slope of dH) and models."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6))
    axes[0].plot(centres, measured * 1e3, "k.-", lw=1, label="measured (slope of dH)")
    for name, rate in models.items():
        axes[0].plot(centres, rate * 1e3, lw=1, label=name)
        axes[1].plot(centres, (rate / measured - 1) * 100, lw=1, label=name)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("dissipated power (mW)")
    axes[1].set_ylabel("model / measured - 1 (%)")
    axes[1].axhline(0, color="k", lw=0.5)
    for ax in axes:
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def soundness_figure(rows, *, bar: float | None = None, title: str = ""):
    """Per recording: the blind law's validation error and the true law's (% of the window's
    dH range), and the law's largest torque at a turning point over the gravity torque there
    (a static friction above 1 would have stopped the joint)."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8))
    x = np.arange(len(rows))
    axes[0].bar(x - 0.2, [r["validation_error_percent"] for r in rows], 0.4,
                label="blind law")
    axes[0].bar(x + 0.2, [r["validation_error_percent_true_law"] for r in rows], 0.4,
                color="0.6", label="true law (measurement's own error)")
    if bar is not None:
        axes[0].axhline(bar, color="k", ls=":", lw=1, label=f"{bar:g} % (target)")
    axes[0].set_ylabel("validation error (% of range)")
    ratios = [max(r["max_static_torque_over_gravity_torque_at_turning_points"], 1e-6)
              for r in rows]
    axes[1].bar(x, ratios, 0.6, color=["tab:green" if v < 1 else "tab:red" for v in ratios])
    axes[1].axhline(1.0, color="k", ls=":", lw=1, label="gravity torque (would stick)")
    axes[1].set_yscale("log")
    axes[1].set_ylabel("static torque / gravity torque")
    for ax in axes:
        ax.set_xticks(x, [r["recording"].replace(", seed", "\nseed") for r in rows],
                      fontsize=6, rotation=60, ha="right")
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    return fig
