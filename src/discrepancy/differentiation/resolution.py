"""Is the sampling fine enough for the chosen differentiation method?

A local polynomial derivative (finite differences, Savitzky–Golay) is biased for content
with few samples per period: a central difference turns the rate of ``sin(ω t)`` into
``sin(ω h) / h``, 8 % slow at 9 samples per period. The check finds, per state, the
frequency below which 95 % of the (detrended) signal's power lies, differentiates a sine of
that frequency on the same sample times with the chosen method, and warns when the
derivative is off by more than :data:`TOLERANCE` and the content has fewer than
:data:`COARSE` samples per period (well-sampled data smoothed on purpose are not warned
about).
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import CoarseSamplingWarning, DiscrepancyError

#: relative error of a sine's derivative above which the sampling is too coarse
TOLERANCE = 0.02
#: samples per period below which content counts as coarsely sampled
COARSE = 20
SHARE = 0.95
ROWS = 4096


def band_edge(t: np.ndarray, x: np.ndarray, share: float = SHARE) -> float:
    """Frequency (1/time) below which ``share`` of the detrended power of ``x`` lies."""
    step = float(np.median(np.diff(t)))
    # the trend on times scaled to [0, 1]: a step of 1e-300 s made the fit's SVD fail
    s = (t - t[0]) / (t[-1] - t[0])
    trend = np.polyval(np.polyfit(s, x, 1), s)
    power = np.abs(np.fft.rfft(x - trend)) ** 2
    cumulative = np.cumsum(power[1:])
    if cumulative.size == 0 or cumulative[-1] <= 0:
        return 0.0
    index = int(np.searchsorted(cumulative, share * cumulative[-1])) + 1
    return float(np.fft.rfftfreq(len(x), step)[min(index, len(power) - 1)])


def warn_if_coarse(method, t: np.ndarray, x: np.ndarray, names) -> None:
    """Warn (CoarseSamplingWarning) for each state ``method`` differentiates badly."""
    t, x = t[:ROWS], x[:ROWS]
    if len(t) < 16:
        return
    step = float(np.median(np.diff(t)))
    trim = max(len(t) // 10, getattr(method, "edge", 0) or 0)
    for j, name in enumerate(names):
        f = band_edge(t, x[:, j])
        if f <= 0 or 1 / (f * step) >= COARSE:
            continue
        omega = 2 * np.pi * f
        probe = np.sin(omega * (t - t[0]) + 0.3)[:, None]
        try:
            _, rate = method.smooth_and_differentiate(probe, t)
        except (DiscrepancyError, ValueError, NotImplementedError):
            return                       # no pointwise derivative (the weak form), or none here
        exact = omega * np.cos(omega * (t - t[0]) + 0.3)
        error = np.max(np.abs(rate[trim:-trim, 0] - exact[trim:-trim])) / omega
        if error > TOLERANCE:
            warnings.warn(
                f"{name} is sampled at about {1 / (f * step):.1f} samples per period of its "
                f"fastest content; {type(method).__name__} misestimates the rate of such a "
                f"signal by {100 * error:.0f} %: use Spectral() for band-limited data, "
                "sample faster, or fit by output error (fit_outputs)",
                CoarseSamplingWarning, stacklevel=5)
