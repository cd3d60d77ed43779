"""Differentiation of fields chosen from the data: the default of a PDE fit.

1. The noise of each field is estimated from high differences along time and along each
   spatial axis (:func:`~discrepancy.differentiation.auto.noise_std` on lines of the grid;
   the smallest estimate over directions, since smooth content only inflates them).
2. Clean fields (noise below :data:`CLEAN` of the field's spread) are fitted pointwise:
   time derivatives by the ODE default (degree-7 Savitzky-Golay, window by GCV), spatial
   ones spectral on periodic axes and by 6th-order differences elsewhere.
3. Noisy fields are fitted in the weak form. Along each axis (time, x, y) the mean power
   spectrum of the data is compared with the white-noise floor the noise estimate implies;
   the *changepoint* is the highest wavenumber still :data:`SIGNAL_OVER_NOISE` times above
   it, and the test function's half-width is the smallest whose Fourier transform there
   is below :data:`FILTER` of its peak (Messenger & Bortz's rule for weak SINDy): the test
   functions pass the signal and filter the noise. Pointwise derivatives that remain in
   the weak form (``u_x²`` of ``u u_xx``) are low-passed at the same changepoint (spectral
   on periodic axes, Savitzky-Golay by GCV elsewhere).

The constants were set on the three examples of ``discrepancy reproduce pde-*`` and checked
on PDEs they were not set on (``tests/test_pde_defaults.py``).
"""
from __future__ import annotations

import numpy as np

from ..differentiation.auto import AutoSmoothing, gcv_window, noise_std
from ..differentiation.spatial import (
    SpatialFiniteDifference,
    SpatialSavitzkyGolay,
    SpatialSpectral,
)
from .weak import FieldWeakForm, bump

#: relative noise (std over the field's spread) below which fields count as clean
CLEAN = 1e-4
#: spectrum / noise floor above which a wavenumber counts as signal
SIGNAL_OVER_NOISE = 10.0
#: the test function's transform at the changepoint, relative to its peak
FILTER = 1e-2
#: lines of the grid sampled per field and axis for the estimates
LINES = 64
#: time half-widths are at most 1/TIME_FRACTION of the record, so that the record holds at
#: least five cross-validation segments of one test function each (:mod:`.solve`)
TIME_FRACTION = 10
#: smallest half-width (samples), and per derivative order in space: the rectangle rule of
#: the kernels stays accurate (∂⁴φ over analytic fields: 2e-6 relative with 20 points,
#: 1e-3 with 12; ∂²φ: 2e-5 with 10, see tests/test_pde_weak.py)
MIN_WIDTH = 10
SAMPLES_PER_ORDER = 5


def _lines(sample, axis: int, field: int, limit: int = 4096) -> list[np.ndarray]:
    """Up to :data:`LINES` series along ``axis`` (0: time, 1..: space) of one field."""
    out = []
    for run in sample:
        a = np.moveaxis(run.u[..., field], axis, -1)
        a = a.reshape(-1, a.shape[-1])[:, :limit]
        pick = np.linspace(0, len(a) - 1, min(LINES, len(a))).astype(int)
        out += list(a[np.unique(pick)])
    return out[:LINES * 2]


def noise_levels(sample, grid) -> tuple[np.ndarray, np.ndarray]:
    """``(noise std, spread)`` per field: the noise from sixth differences along every
    direction (smallest), the spread as the fields' standard deviation."""
    n = sample[0].n_fields
    noise, spread = np.zeros(n), np.zeros(n)
    for j in range(n):
        estimates = []
        for axis in range(grid.ndim + 1):
            squares = [noise_std(np.stack(lines, axis=1)) ** 2 for run in sample
                       if len(lines := [x for x in _lines([run], axis, j) if len(x) > 12])]
            if squares:
                estimates.append(float(np.sqrt(np.mean([np.mean(s) for s in squares]))))
        noise[j] = min(estimates) if estimates else 0.0
        spread[j] = float(np.sqrt(np.mean([np.var(r.u[..., j]) for r in sample])))
    return noise, spread


def changepoint(lines: list[np.ndarray], sigma: float, periodic: bool) -> float:
    """Fraction of the Nyquist wavenumber up to which the lines' mean spectrum stands
    :data:`SIGNAL_OVER_NOISE` above the white-noise floor of ``sigma``."""
    x = np.stack(lines)
    n = x.shape[1]
    if periodic:
        taper = np.ones(n)
    else:
        s = np.linspace(-1, 1, n)
        x = x - np.polynomial.polynomial.polyval(s, np.polynomial.polynomial.polyfit(
            s, x.T, 1)).reshape(x.shape)
        taper = np.hanning(n)
    power = np.mean(np.abs(np.fft.rfft(x * taper, axis=1)) ** 2, axis=0)
    floor = sigma ** 2 * np.sum(taper ** 2)
    above = np.flatnonzero(power[1:] > SIGNAL_OVER_NOISE * max(floor, 1e-300)) + 1
    if above.size == 0:
        return 1.0 / (n // 2)
    return float(above.max()) / (len(power) - 1)


def half_width(fraction: float, power: int, limit: int, least: int) -> int:
    """Smallest half-width (samples, from ``least`` to ``limit``) whose bump's transform at
    ``fraction`` of the Nyquist wavenumber is below :data:`FILTER` of its value at 0."""
    omega = np.pi * fraction
    for width in range(least, max(least, limit) + 1):
        phi = bump(width, power, 0, 1.0)
        j = np.arange(-width, width + 1)
        if abs(phi @ np.cos(omega * j)) <= FILTER * phi.sum():
            return width
    return max(least, limit)


def choose(sample, grid, order: int, shortest: int, *, spatial=None,
           weak: FieldWeakForm | None = None):
    """``(time_methods, spatial, choice)`` for the data ``sample`` (see the module
    docstring; ``shortest``: snapshots of the shortest run); ``weak``: a weak form asked
    for, whose missing widths are chosen."""
    noise, spread = noise_levels(sample, grid)
    relative = noise / np.where(spread > 0, spread, 1.0)
    info = {"noise_std": noise.tolist(), "relative_noise": relative.tolist()}
    if weak is None and np.all(relative <= CLEAN):
        methods, time_info = time_smoothing(sample, AutoSmoothing())
        spatial = spatial or tuple(SpatialSpectral() if p else SpatialFiniteDifference(6)
                                   for p in grid.periodic)
        return methods, spatial, {**info, **time_info, "form": "pointwise",
                                  "chosen_by": "noise below 1e-4 of the fields' spread: "
                                               "pointwise (GCV Savitzky-Golay in time)"}
    power = weak.power if weak is not None and weak.power is not None else max(8, 2 * order + 2)
    sigma = float(np.max(noise))
    fractions, widths = [], []
    lengths = [shortest, *grid.shape]
    for axis in range(grid.ndim + 1):
        periodic = axis > 0 and grid.periodic[axis - 1]
        fraction = max(changepoint([x for j in range(run.n_fields)
                                    for x in _lines([run], axis, j)], sigma, periodic)
                       for run in sample)
        # a non-periodic axis loses a half-width at each end to the test functions
        limit = (lengths[axis] // 2 - 1) if periodic else (lengths[axis] - 1) // 8
        if axis == 0:       # time: blocked cross-validation needs supports short of a fold
            limit = lengths[0] // TIME_FRACTION
        fractions.append(fraction)
        # time: short records trade the quadrature's accuracy for five CV segments
        least = max(3, min(MIN_WIDTH, limit)) if axis == 0 else max(
            MIN_WIDTH, SAMPLES_PER_ORDER * order)
        widths.append(half_width(fraction, power, limit, least))
    if weak is not None and weak.widths is not None:
        widths = [int(w) for w in weak.widths]
    stride = None if weak is None else weak.stride
    debias = noise.tolist() if weak is None or weak.noise_std is None else weak.noise_std
    form = FieldWeakForm(widths, power=power, stride=stride, noise_std=debias)
    spatial = spatial or tuple(_smoother(sample, grid, axis, fractions[axis + 1])
                               for axis in range(grid.ndim))
    return (form,), spatial, {**info, "form": "weak", "widths": widths,
                              "changepoint_fraction_of_nyquist": fractions,
                              "chosen_by": "noise above 1e-4 of the fields' spread: weak form "
                                           "(test functions filter beyond the spectra's "
                                           "changepoint)"}


def _smoother(sample, grid, axis: int, fraction: float):
    """The spatial method for pointwise terms left in the weak form along ``axis``."""
    if grid.periodic[axis]:
        return SpatialSpectral(cutoff=min(1.0, max(fraction, 1e-3)))
    lines = [x for j in range(sample[0].n_fields) for x in _lines(sample, axis + 1, j)]
    limit = (grid.shape[axis] // 4) // 2 * 2 - 1
    if limit < 9:
        return SpatialFiniteDifference(6)
    window, _ = gcv_window(lines, 7, limit)
    return SpatialSavitzkyGolay(max(9, window), 7)


def time_smoothing(sample, method):
    """One time differentiator per field chosen by ``method`` (a data-driven one, e.g.
    :class:`~discrepancy.differentiation.AutoSmoothing`) from lines of the grid."""
    methods, info = [], {"window_length": []}
    for j in range(sample[0].n_fields):
        series = [(run.t[:len(x)], x[:, None]) for run in sample
                  for x in _lines([run], 0, j, limit=len(run.t))]
        chosen, detail = method.choose(series)
        methods.append(chosen)
        info["window_length"].append(detail.get("window_length"))
    return tuple(methods), info
