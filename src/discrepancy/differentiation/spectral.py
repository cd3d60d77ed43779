"""Spectral (FFT) differentiation for periodic or band-limited signals on uniform grids."""
from __future__ import annotations

import numpy as np

from ..constraints import Interval, Real
from .base import Differentiator, register


@register("spectral")
class Spectral(Differentiator):
    """Derivative by the discrete Fourier transform (numpy ``rfft``): exact for
    band-limited periodic samples, as PySINDy's ``SpectralDerivative``.

    Args:
        cutoff: keep frequencies up to this fraction of the Nyquist frequency (1: all); a
            sharp low-pass for noisy data. The smoothed x is the same low-passed signal.

    The record is treated as one period: a signal whose ends do not join smoothly gets
    ringing near them (use it for periodic or windowed data). Needs uniform ``t``; a global
    method (cannot be applied chunk by chunk).
    """

    uniform_only = True
    _parameter_constraints = {"cutoff": [Interval(Real, 0, 1, closed="right")]}

    def __init__(self, cutoff: float = 1.0):
        self.cutoff = cutoff

    def _compute(self, x, t):
        m = x.shape[0]
        dt = (t[-1] - t[0]) / (m - 1)
        spectrum = np.fft.rfft(x, axis=0)
        freq = np.fft.rfftfreq(m, d=dt)
        keep = freq <= self.cutoff * freq[-1] + 1e-12 * freq[-1]
        spectrum[~keep] = 0.0
        derivative = 2j * np.pi * freq[:, None] * spectrum
        if m % 2 == 0:  # the Nyquist term's derivative is not representable: drop it
            derivative[-1] = 0.0
        smooth = np.fft.irfft(spectrum, n=m, axis=0) if self.cutoff < 1 else x
        return smooth, np.fft.irfft(derivative, n=m, axis=0)
