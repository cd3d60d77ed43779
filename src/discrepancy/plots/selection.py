"""Figure of the automatic threshold choice: cross-validated error against model size."""
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
