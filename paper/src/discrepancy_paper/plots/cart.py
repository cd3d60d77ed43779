"""Figures of cart swing-ups: pendulum snapshots (like the paper's Fig. 6), time series,
robustness study, and an animated GIF of several runs side by side."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Rectangle
from PIL import Image

CART_W, CART_H = 0.10, 0.05


def _draw(ax, pts, alpha, color):
    """One pose: cart rectangle and two links from ``pts`` ``(3, 2)`` (cart, elbow, tip)."""
    cart = Rectangle((pts[0, 0] - CART_W / 2, -CART_H / 2), CART_W, CART_H, fc="0.8", ec="0.3",
                     alpha=alpha, lw=0.8)
    ax.add_patch(cart)
    ax.plot(pts[:, 0], pts[:, 1], "-o", color=color, alpha=alpha, lw=2, ms=3)


def _frame(ax, rail, title):
    ax.axhline(0, color="0.6", lw=0.8, zorder=0)
    ax.axvline(-rail, color="tab:red", lw=0.8, ls=":")
    ax.axvline(rail, color="tab:red", lw=0.8, ls=":")
    ax.set_aspect("equal")
    ax.set_ylim(-0.6, 0.6)
    ax.set_title(title, fontsize=9)


def snapshots_figure(runs: dict, points, *, every=0.15, rail=0.5):
    """One row per run: the pendulum drawn every ``every`` seconds, darker as time goes on.

    Args:
        runs: ``{label: (t (k,), x (k, 6))}``.
        points: callable ``x (k, 6) -> (k, 3, 2)`` (e.g. ``DoublePendulumOnCart.points``).
        rail: cart travel limit (m), drawn as dotted lines.
    """
    cols = min(3, len(runs))
    rows = -(-len(runs) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.0 * rows), squeeze=False)
    for ax in axes.ravel()[len(runs):]:
        ax.set_visible(False)
    for ax, (label, (t, x)) in zip(axes.ravel(), runs.items(), strict=False):
        idx = np.unique(np.searchsorted(t, np.arange(0.0, t[-1] + 1e-9, every)).clip(0, len(t) - 1))
        idx = np.append(idx, len(t) - 1) if idx[-1] != len(t) - 1 else idx
        pts = points(x[idx])
        for j, p in enumerate(pts):
            _draw(ax, p, 0.15 + 0.85 * j / max(len(pts) - 1, 1), plt.cm.viridis(j / len(pts)))
        lo = min(-rail - 0.1, pts[..., 0].min() - 0.1)
        hi = max(rail + 0.1, pts[..., 0].max() + 0.1)
        ax.set_xlim(lo, hi)
        _frame(ax, rail, label)
    fig.supxlabel("horizontal position (m); colour and opacity: time (early → late)", fontsize=9)
    fig.tight_layout()
    return fig


def time_series_figure(runs: dict, *, plans: dict | None = None):
    """Angles, cart position and input of several runs ``{label: (t, x, t_u, u)}``;
    ``plans`` (same layout) are drawn dashed."""
    fig, axes = plt.subplots(4, 1, figsize=(9, 8.5), sharex=True)
    labels = ["φ1 (rad)", "φ2 (rad)", "s (m)", "u = s̈ (m/s²)"]
    seen = []
    for style, group in (("-", runs), ("--", plans or {})):
        for label, (t, x, tu, u) in group.items():
            color = f"C{len(seen)}"
            seen.append(label)
            for row, col in enumerate((0, 1, 2)):
                axes[row].plot(t, x[:, col], style, color=color, lw=1.1,
                               label=label if row == 0 else None)
            axes[3].step(tu, u, style, where="post", color=color, lw=0.9)
    for ax, label in zip(axes, labels, strict=True):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[:2]:  # a tumbling run would squash the others; show -2..5.5 rad only
        lo, hi = ax.get_ylim()
        if lo < -2 or hi > 5.5:
            ax.set_ylim(max(lo, -2.0), min(hi, 5.5))
            ax.text(0.99, 0.03, "axis clipped to [-2, 5.5] rad", transform=ax.transAxes,
                    ha="right", fontsize=7, color="0.4")
    axes[0].legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    return fig


def robustness_figure(final_errors: dict, success: dict, *, angle_tol=0.05):
    """Left: success rate per strategy. Right: final max |φ| per perturbed case (log scale)."""
    names = list(final_errors)
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.2),
                               gridspec_kw={"width_ratios": [1, 1.3]})
    rates = [100 * np.mean(success[n]) for n in names]
    a.barh(names, rates, color=["tab:green" if r >= 96 else "tab:red" for r in rates])
    a.set_xlim(0, 100)
    a.set_xlabel("success rate (%)")
    a.invert_yaxis()
    for i, r in enumerate(rates):
        a.text(min(r + 1, 88), i, f"{r:.0f} %", va="center", fontsize=8)
    for i, n in enumerate(names):
        e = np.maximum(np.asarray(final_errors[n]), 1e-12)
        b.scatter(e, np.full(len(e), i) + np.random.default_rng(i).uniform(-0.2, 0.2, len(e)),
                  s=10, alpha=0.7)
    b.axvline(angle_tol, color="k", ls="--", lw=0.8, label=f"success limit {angle_tol} rad")
    b.set_xscale("log")
    b.set_yticks(range(len(names)), [""] * len(names))
    b.invert_yaxis()
    b.set_xlabel("final max(|φ1|, |φ2|) at T (rad)")
    b.legend(fontsize=8)
    fig.tight_layout()
    return fig


def swingup_gif(path, runs: dict, points, *, fps=20, rail=0.5, dpi=72):
    """Animated GIF of several runs side by side; ``runs = {label: (t, x)}`` sharing ``t``.
    Dotted red lines: the rail's ends; the panel is ±(rail + 0.15) m wide or wider.

    Each frame is drawn once and handed to Pillow, as matplotlib's ``PillowWriter`` does;
    ``FuncAnimation.save`` would draw every frame twice (once at the screen's dpi, once at
    ``dpi``): the same GIF at about half the CPU time (measured on the cart-mpc GIF)."""
    labels = list(runs)
    t = runs[labels[0]][0]
    frames = np.unique(np.searchsorted(t, np.arange(0.0, t[-1] + 1e-9, 1.0 / fps)).clip(0,
                                                                                      len(t) - 1))
    cols = 2 if len(labels) > 2 else len(labels)
    rows = -(-len(labels) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.4 * cols, 2.9 * rows), squeeze=False)
    for ax in axes.ravel()[len(labels):]:
        ax.set_visible(False)
    axes = axes.ravel()[:len(labels)]
    pts = {k: points(runs[k][1]) for k in labels}
    width = max(rail + 0.15, max(np.abs(p[..., 0]).max() for p in pts.values()) + 0.1)
    artists = []
    for ax, k in zip(axes, labels, strict=True):
        ax.set_xlim(-width, width)
        _frame(ax, rail, k)
        ax.set_xticks([])  # tick labels would be re-laid out on every frame (slow)
        ax.set_yticks([])
        cart = ax.add_patch(Rectangle((0, -CART_H / 2), CART_W, CART_H, fc="0.8", ec="0.3"))
        (links,) = ax.plot([], [], "-o", color="tab:blue", lw=2, ms=3)
        clock = ax.text(0.03, 0.88, "", transform=ax.transAxes, fontsize=8,
                        bbox={"fc": "w", "ec": "none", "alpha": 0.8})
        artists.append((k, cart, links, clock))
    fig.tight_layout()

    def draw(i):
        j = frames[i]
        for k, cart, links, clock in artists:
            p = pts[k][j]
            cart.set_x(p[0, 0] - CART_W / 2)
            links.set_data(p[:, 0], p[:, 1])
            clock.set_text(f"t = {t[j]:.2f} s")
        return []

    fig.set_dpi(dpi)
    images = []
    for i in range(len(frames)):
        draw(i)
        fig.canvas.draw()
        images.append(Image.frombuffer("RGBA", fig.canvas.get_width_height(),
                                       fig.canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
                      .convert("RGB"))
    plt.close(fig)
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps),
                   loop=0)
    return path
