"""Figures of the constrained swing-up campaigns: runs against the rail, a leaderboard,
coefficients across learning attempts, MPC solve times, success maps over a grid."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap


def runs_figure(runs: dict, *, angles, position, rail, u_max, labels):
    """Angles, cart position (rail dotted) and input of several closed-loop runs.

    Args:
        runs: ``{label: ClosedLoopRun}``; angles: state indices; position: the cart's index.
        labels: axis labels of the angles.
    """
    rows = len(angles) + 2
    fig, axes = plt.subplots(rows, 1, figsize=(9, 2.0 * rows), sharex=True)
    for k, (name, run) in enumerate(runs.items()):
        t = np.append(run.t_dense[:, :-1].ravel(), run.t[-1])
        x = np.vstack([run.x_dense[:, :-1].reshape(-1, run.x.shape[1]), run.x[-1]])
        for ax, i in zip(axes, [*angles, position], strict=False):
            ax.plot(t, x[:, i], color=f"C{k}", lw=1.1, label=name)
        axes[-1].step(run.t[:-1], run.u[:, 0], where="post", color=f"C{k}", lw=0.9)
    for ax, label in zip(axes, [*labels, "s (m)", "u (m/s²)"], strict=True):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[:len(angles)]:
        lo, hi = ax.get_ylim()
        ax.set_ylim(max(lo, -2.0), min(hi, 5.5))
    axes[len(angles)].set_ylim(-2.5 * rail, 2.5 * rail)
    for sign in (-1, 1):
        axes[len(angles)].axhline(sign * rail, color="tab:red", ls=":", lw=1)
        axes[-1].axhline(sign * u_max, color="tab:red", ls=":", lw=1)
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    return fig


def leaderboard_figure(study: dict, controllers, *, rail):
    """Left: successes (rail included) and final states reached (rail ignored) per
    controller. Right: each case's largest cart travel per controller against the rail."""
    n = study["n_cases"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 3.8), gridspec_kw={"width_ratios": [1, 1.2]})
    y = np.arange(len(controllers))
    ok = [study["success_counts"][c] for c in controllers]
    reached = [study["final_state_reached_counts"][c] for c in controllers]
    a.barh(y + 0.2, reached, height=0.4, color="0.75", label="upright at the end (rail ignored)")
    a.barh(y - 0.2, ok, height=0.4, color="tab:green", label="success: upright AND limits kept")
    for i, (c, r) in enumerate(zip(ok, reached, strict=True)):
        a.text(c + 0.5, i - 0.2, f"{c}/{n}", va="center", fontsize=8)
        a.text(r + 0.5, i + 0.2, f"{r}/{n}", va="center", fontsize=8, color="0.4")
    a.set_yticks(y, controllers)
    a.set_xlim(0, n * 1.18)
    a.invert_yaxis()
    a.set_xlabel(f"perturbed true systems (of {n})")
    a.legend(fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, frameon=False)
    for i, c in enumerate(controllers):
        travel = [r[c]["max_abs_s"] for r in study["cases"]]
        b.scatter(travel, np.full(n, i) + np.random.default_rng(i).uniform(-0.2, 0.2, n), s=10,
                  alpha=0.7)
    b.axvline(rail, color="tab:red", ls="--", lw=1, label=f"rail ±{rail} m")
    b.set_xscale("log")
    b.set_yticks(y, [""] * len(controllers))
    b.invert_yaxis()
    b.set_xlabel("largest |s| of the run (m)")
    b.legend(fontsize=8)
    fig.tight_layout()
    return fig


def learning_figure(learning: dict, terms: dict):
    """Each term's coefficient in the model used at each attempt, over its exact value
    (``terms``: ``{label: (state, term, exact)}``; attempt 1 uses the prior, so 0), one
    panel per system; successful attempts are green."""
    fig, axes = plt.subplots(1, len(learning), figsize=(4.4 * len(learning), 3.2),
                             squeeze=False, sharey=True)
    for ax, (name, summary) in zip(axes[0], learning.items(), strict=True):
        rows = summary["coefficients_after_each_attempt"]
        attempts = [r["attempt"] for r in rows]
        for k, (label, (state, term, exact)) in enumerate(terms.items()):
            used = [0.0] + [r["coefficients_after"][state].get(term, 0.0) / exact
                            for r in rows[:-1]]
            ax.plot(attempts, used, "-o", color=f"C{k}", label=label, ms=5)
        ok = [r["attempt"] for r in rows if r["success"]]
        ax.scatter(ok, [1.0] * len(ok), s=160, facecolors="none", edgecolors="tab:green",
                   lw=2, label="attempt succeeded")
        ax.axhline(1.0, color="0.5", ls=":", lw=1)
        ax.set_xticks(attempts)
        ax.set_title(f"{name}: success at attempt {summary['attempts_to_success']}", fontsize=9)
        ax.set_xlabel("attempt")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("coefficient in the model used / exact value")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def solve_time_figure(times: dict, *, period):
    """Histogram of CPU time per sample (ms) of each controller ``{label: seconds}``; the
    control period dashed."""
    fig, ax = plt.subplots(figsize=(7.5, 3.4))
    everything = 1e3 * np.concatenate([np.asarray(v, dtype=float) for v in times.values()])
    bins = np.logspace(np.log10(max(everything.min(), 0.05)),
                       np.log10(max(everything.max(), 1e3 * period)) + 0.05, 50)
    for k, (label, seconds) in enumerate(times.items()):
        ms = 1e3 * np.asarray(seconds, dtype=float)
        ax.hist(ms, bins=bins, alpha=0.6, color=f"C{k}",
                label=f"{label}: median {np.median(ms):.2f} ms, worst {ms.max():.1f} ms")
    ax.axvline(1e3 * period, color="tab:red", ls="--", label=f"control period {1e3 * period:g} ms")
    ax.set_xscale("log")
    ax.set_xlabel("CPU time per sample (ms)")
    ax.set_ylabel("samples")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def estimation_figure(run, estimates, stds, names, *, states):
    """A filter's estimation error on ``states`` of a closed-loop run (at the control
    samples) within its own ±2σ band, one panel per state, beside the true state (right
    axis, grey) for scale; RMS error in each title."""
    fig, axes = plt.subplots(len(states), 1, figsize=(9, 1.9 * len(states)), sharex=True,
                             squeeze=False)
    t = run.t[:len(estimates)]
    for ax, i in zip(axes[:, 0], states, strict=True):
        true = run.x[:len(estimates), i]
        error, band = estimates[:, i] - true, 2 * stds[:, i]
        ax.fill_between(t, -band, band, color="C1", alpha=0.25, lw=0, label="±2σ (the filter's)")
        ax.plot(t, error, color="C1", lw=0.9, label="estimate − true")
        twin = ax.twinx()
        twin.plot(t, true, color="0.6", lw=0.8)
        twin.set_ylabel(f"{names[i]} (true)", color="0.5", fontsize=8)
        rms = float(np.sqrt(np.mean(error ** 2)))
        ax.set_title(f"{names[i]}: RMS error {rms:.3g}, {np.mean(np.abs(error) <= band):.0%} "
                     "of samples within ±2σ", fontsize=9)
        ax.set_ylabel("error")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("t (s)")
    fig.tight_layout()
    return fig


def success_maps_figure(maps: dict, *, rows: list, cols: list, panels: list, row_label: str,
                        col_label: str):
    """One heat map per controller and panel: ``maps[controller][panel]`` is a
    ``(len(rows), len(cols))`` array of success (1), failure (0) or not run (nan)."""
    controllers = list(maps)
    fig, axes = plt.subplots(len(controllers), len(panels),
                             figsize=(2.6 * len(panels) + 1, 1.9 * len(controllers) + 0.6),
                             squeeze=False, sharex=True, sharey=True)
    cmap = ListedColormap(["tab:red", "tab:green"])
    for i, c in enumerate(controllers):
        total = sum(np.nansum(maps[c][p]) for p in panels)
        cells = sum(np.sum(np.isfinite(maps[c][p])) for p in panels)
        for j, p in enumerate(panels):
            ax = axes[i, j]
            ax.imshow(maps[c][p], cmap=cmap, vmin=0, vmax=1, aspect="auto")
            ax.set_xticks(range(len(cols)), cols, fontsize=7)
            ax.set_yticks(range(len(rows)), rows, fontsize=7)
            ax.set_xticks(np.arange(len(cols) + 1) - 0.5, minor=True)
            ax.set_yticks(np.arange(len(rows) + 1) - 0.5, minor=True)
            ax.grid(which="minor", color="white", lw=2)
            ax.tick_params(which="minor", length=0)
            if i == 0:
                ax.set_title(p, fontsize=9)
            if j == 0:
                ax.set_ylabel(f"{c}\n{int(total)}/{cells}\n{row_label}", fontsize=8)
    fig.supxlabel(col_label, fontsize=9)
    fig.tight_layout()
    return fig
