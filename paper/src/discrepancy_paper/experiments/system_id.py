"""Pieces shared by the system-identification benchmarks' reports."""
from __future__ import annotations

import numpy as np


def published_table(rep, record: str, ours: float, unit: str, published: dict) -> None:
    """Our figure on ``record`` beside published ones (as reported by their authors)."""
    rows = [["this model (discrepancy)", f"{ours:.3f}"]]
    rows += [[name, f"{value:.3g}"] for name, value in
             sorted(published.items(), key=lambda item: item[1])]
    rep.text(f"Beside published results on the same record ({record}; figures as their "
             "authors report them, not rerun here):")
    rep.table(["model", f"RMS simulation error ({unit})"], rows)


def support_path_figure(path):
    """Held-out forecast error (RMS, scaled) against the number of terms on the path, with
    one standard error, the chosen support marked."""
    import matplotlib.pyplot as plt

    from discrepancy.models.outputs.output_fit import choose

    terms = np.array([s.n_terms for s in path])
    error = np.array([s.heldout_error for s in path])
    spread = np.array([s.heldout_se for s in path]) / (2 * np.maximum(error, 1e-300))
    chosen = choose(path, None)
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.errorbar(terms, error, yerr=spread, fmt="o-", ms=4, capsize=2)
    ax.plot([chosen.n_terms], [chosen.heldout_error], "r*", ms=14, label="chosen")
    ax.set_yscale("log")
    ax.set_xlabel("number of terms")
    ax.set_ylabel("held-out forecast error (scaled RMS)")
    ax.legend()
    return fig
