"""Smoothing chosen from the data: the default differentiation method.

:class:`AutoSmoothing` looks at (a sample of) the measured states and returns a concrete
method: Savitzky–Golay of degree ``polyorder`` (7) with each state's window chosen by
generalized cross-validation (GCV) of the smoothed states, or, for non-uniform times, a
cubic smoothing spline whose smoothing GCV chooses (scipy's ``make_smoothing_spline``).

GCV scores how well each sample is predicted by the smoother with that sample left out
(for a linear smoother ``S`` it is ``mean((x - S x)^2) / (1 - S_ii)^2``, and a
Savitzky–Golay filter's ``S_ii`` is its central coefficient), so the window is chosen from
the states alone and never from the model's answer. On noise-free data it picks the
shortest window, where a degree-7 filter is exact to ~1e-10; with noise it picks the
window where the smoothing error and the noise it passes balance for each sample.

The regression then uses half that window (:data:`REGRESSION_SCALE`): it averages the
noise that a shorter window lets through over all samples, but not the bias that a longer
one puts into every sample. Both numbers were chosen on four training systems (Van der
Pol, Lorenz, Duffing, Lotka-Volterra; 0-20 % noise, 10 seeds): degree 7 gave the best
coefficients of degrees 3-7, and fractions 0.35-0.6 of the GCV window all beat the whole
window (Duffing at 20 % noise: right terms in 10/10 seeds against 8/10, error 3.3 % against
6.7 %). ``benchmarks/bench_defaults.py`` checks them on systems they were not chosen on.

The noise level of each state is estimated too (from 6th differences, robustly) and
reported with the choice; written by hand because no library we use does either.
"""
from __future__ import annotations

from math import comb

import numpy as np

from ..constraints import Integral, Interval, Predicate
from ..data.validation import is_uniform
from ..errors import ShapeError
from .base import Differentiator, register
from .finite_difference import FiniteDifference
from .methods import MAX_POLYORDER, ODD_WINDOW, SavitzkyGolay
from .savgol import savgol, savgol_coefficients
from .spline import SmoothingSpline

ODD_DEGREE = Predicate(lambda p: isinstance(p, (int, np.integer)) and not isinstance(p, bool)
                       and 3 <= p <= MAX_POLYORDER and p % 2 == 1,
                       f"an odd integer >= 3 and <= {MAX_POLYORDER}")
#: the window used is this fraction of the GCV-best one (see the module docstring)
REGRESSION_SCALE = 0.5
#: consecutive windows of rising GCV after which the search stops
PATIENCE = 4
GROWTH = 1.2


def noise_std(x: np.ndarray, order: int = 6) -> np.ndarray:
    """Robust estimate of white measurement noise per column of ``x`` ``(m, n)``: the median
    absolute ``order``-th difference, scaled to a Gaussian standard deviation. Smooth signals
    sampled finely contribute almost nothing to high differences."""
    d = np.diff(x, n=order, axis=0)
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    return mad / 0.6745 / np.sqrt(comb(2 * order, order))


def gcv_score(columns: list[np.ndarray], window: int, polyorder: int) -> float:
    """GCV of a Savitzky–Golay smoother over the interior samples of several series."""
    centre = savgol_coefficients(window, polyorder)[window // 2]
    h = window // 2
    sq, count = 0.0, 0
    for x in columns:
        r = x[h:len(x) - h] - savgol(x, window, polyorder)[h:len(x) - h]
        sq, count = sq + float(r @ r), count + len(r)
    return sq / count / (1 - centre) ** 2


def gcv_window(columns: list[np.ndarray], polyorder: int, max_window: int) -> tuple[int, dict]:
    """The window of least GCV for one state (series ``columns``), and the scores tried."""
    scores, best, rising = {}, None, 0
    window = polyorder + 2
    while window <= max_window:
        scores[window] = gcv_score(columns, window, polyorder)
        if best is None or scores[window] < scores[best]:
            best, rising = window, 0
        else:
            rising += 1
            if rising >= PATIENCE:
                break
        window = max(window + 2, int(window * GROWTH) // 2 * 2 + 1)
    return best, scores


@register("auto")
class AutoSmoothing(Differentiator):
    """Differentiation chosen from the data (see the module docstring).

    Args:
        polyorder: odd degree of the Savitzky–Golay polynomials (7).
        max_window: longest window tried (default: a quarter of the shortest sampled
            trajectory).
        sample_rows: the choice looks at the first ``sample_rows`` samples of the data
            (over all trajectories, in order).

    Used inside a model it is resolved once per fit (:meth:`choose`); the concrete method
    and the reasons (noise estimates, windows) are stored on the fitted model.
    """

    data_driven = True
    _parameter_constraints = {"polyorder": [ODD_DEGREE],
                              "max_window": [None, ODD_WINDOW],
                              "sample_rows": [Interval(Integral, 100, None)]}

    def __init__(self, polyorder: int = 7, *, max_window: int | None = None,
                 sample_rows: int = 100_000):
        self.polyorder = polyorder
        self.max_window = max_window
        self.sample_rows = sample_rows

    def choose(self, series) -> tuple[Differentiator, dict]:
        """The method for data ``series`` (a list of ``(t, x)`` with ``x`` ``(m, n)``) and
        a description of the choice: ``{"chosen_by", "noise_std", ...}``."""
        self._validate_params()
        sample = _first_rows(series, self.sample_rows)
        n = sample[0][1].shape[1]
        usable = [x for _, x in sample if len(x) > 12]
        noise = np.sqrt(np.mean([noise_std(x) ** 2 for x in usable], axis=0)) if usable \
            else np.zeros(n)
        if not all(is_uniform(t) for t, _ in sample):
            return SmoothingSpline(), {"chosen_by": "GCV (smoothing spline: non-uniform t)",
                                       "noise_std": noise.tolist()}
        shortest = min(len(x) for _, x in sample)
        limit = (shortest // 4) // 2 * 2 - 1
        if self.max_window is not None:
            limit = min(limit, self.max_window)
        if limit < self.polyorder + 2:
            return self._too_short(shortest)
        windows, best, scores = [], [], []
        for j in range(n):
            w, s = gcv_window([x[:, j] for _, x in sample], self.polyorder, limit)
            best.append(w)
            windows.append(max(self.polyorder + 2, int(w * REGRESSION_SCALE) // 2 * 2 + 1))
            scores.append({str(k): v for k, v in s.items()})
        method = SavitzkyGolay(window_length=windows, polyorder=self.polyorder)
        return method, {"chosen_by": "GCV", "noise_std": noise.tolist(),
                        "window_length": windows, "gcv_window": best, "gcv": scores}

    def _too_short(self, shortest: int) -> tuple[Differentiator, dict]:
        """PySINDy's default (second-order finite differences) for records too short to
        choose a window from, with a warning (:mod:`discrepancy.short_records`)."""
        from ..short_records import too_short

        if self.max_window is not None and self.max_window < self.polyorder + 2:
            raise ShapeError(f"AutoSmoothing: max_window={self.max_window} leaves no window of "
                             f"degree {self.polyorder} to choose (it needs at least "
                             f"{self.polyorder + 2})")
        need = 4 * (self.polyorder + 3)  # a quarter of the record holds the longest window
        too_short(f"AutoSmoothing (a window of degree {self.polyorder} chosen by GCV)",
                  shortest, need, unit="samples in the shortest trajectory",
                  fallback="FiniteDifference() (second order, no smoothing)")
        return FiniteDifference(), {"chosen_by": f"the short-record fallback ({shortest} "
                                                 "samples, too few for GCV)"}

    def _compute(self, x, t):
        method, _ = self.choose([(t, x)])
        return method.smooth_and_differentiate(x, t)


def _first_rows(series, budget: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The first ``budget`` rows of the data, whole trajectories first (the last one cut)."""
    out = []
    for t, x in series:
        if budget <= 0:
            break
        out.append((t[:budget], x[:budget]))
        budget -= len(x)
    return out
