"""The smoothing of positions an energy fit needs, chosen from the recording itself.

``dH = H_m(x_0) - H_m(x)`` is evaluated on smoothed angles and their derivatives; its error
is pointwise noise (quantisation and sensor noise through ``dq``) where the smoothing is too
short, and bias (peaks of speed flattened, so ``T`` dips at every fast passage) where it is
too long. Both make ``dH`` wiggle, while the energy truly lost only grows, smoothly on the
scale of a second. :func:`choose_smoothing` takes the Savitzky-Golay filter whose ``dH``
departs least from its own one-second moving average (RMS). Chosen on the training part of
17 simulated encoder recordings (one to three links), it kept the error of ``H_m`` within
1.0-1.5 times (median 1.0) that of the best filter of the grid in hindsight, where the fixed
default window (31 samples, cubic) was 1.2-10 times it (median 4).
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter1d

from ..data.trajectory import as_2d, as_times
from ..differentiation import SavitzkyGolay
from ..errors import DataError

#: candidate windows (samples) and degrees of the Savitzky-Golay filter
WINDOWS = (21, 31, 51, 71, 101, 151, 201)
DEGREES = (3, 5, 7)
#: the moving average the wiggle of dH is measured against (s)
AVERAGE_SECONDS = 1.0


def smoothing_scores(energy, q, t, *, windows=WINDOWS, degrees=DEGREES) -> dict:
    """``{(window, degree): RMS of dH - its moving average (J)}`` for every candidate filter
    that fits at least 20 times into the record."""
    q = as_2d("q", q, allow_1d=True)
    t = as_times("t", t, len(q))
    dt = float(np.median(np.diff(t)))
    average = max(3, int(round(min(AVERAGE_SECONDS, (t[-1] - t[0]) / 20) / dt)))
    scores = {}
    for window in windows:
        if 20 * window > len(q):
            continue
        for degree in degrees:
            if degree >= window - 2:
                continue
            smoother = SavitzkyGolay(window_length=window, polyorder=degree)
            smooth, rate = smoother.smooth_and_differentiate(q, t)
            keep = slice(smoother.edge, len(q) - smoother.edge)
            h = np.asarray(energy(np.hstack([smooth, rate])[keep]), float)
            scores[window, degree] = float(np.sqrt(np.mean(
                (h - uniform_filter1d(h, average, mode="nearest")) ** 2)))
    return scores


def choose_smoothing(energy, q, t, *, windows=WINDOWS, degrees=DEGREES) -> SavitzkyGolay:
    """The Savitzky-Golay filter (of ``windows`` x ``degrees``) whose ``dH`` wiggles least
    (see the module docstring); ``q`` ``(m, k)`` positions at times ``t`` (s)."""
    scores = smoothing_scores(energy, q, t, windows=windows, degrees=degrees)
    if not scores:
        raise DataError(f"the record ({len(np.atleast_1d(t))} samples) is too short for "
                        f"any smoothing window of {list(windows)} (each needs 20 windows)")
    window, degree = min(scores, key=scores.get)
    return SavitzkyGolay(window_length=window, polyorder=degree)
