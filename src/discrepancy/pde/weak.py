"""The weak form for fields: every term integrated against space-time test functions.

Test functions are products ``φ(t, x, y) = ψ((t - t_c)/H_t) ψ((x - x_c)/H_x) ...`` of the
bump ``ψ(τ) = (1 - τ²)^q`` (``q = power``), one per centre. Integration by parts moves
the time derivative and, through :func:`~discrepancy.pde.divergence.divergence_form`, as
many spatial derivatives as possible onto ``φ``:

    -∫ φ_t u - ∫ φ N_m = Σ_j ξ_j ∫ φ θ_j,   ∫ φ ∂^β h = (-1)^|β| ∫ (∂^β φ) h,

so noise meets smooth kernels instead of being differentiated. Centres lie at every time
sample (rows whose support leaves the run are zero, as in the ODE weak form, so a run cut
into time chunks with ``halo = H_t`` samples gives the same sums) and every ``stride``-th
grid point (all of a periodic axis; those whose support fits on a non-periodic one).
Integrals are rectangle rules: spatial ones as strided window sums (numpy), temporal ones
by FFT (scipy ``oaconvolve``). Written here because PySINDy's ``WeakPDELibrary`` samples
random sub-domains of one array and is not an operator on time chunks.
"""
from __future__ import annotations

from dataclasses import dataclass
from math import comb

import numpy as np
import sympy as sp

from ..base import Estimator
from ..constraints import Integral, Interval, Predicate, Real
from ..errors import ShapeError
from ..symbolic import compile_numpy
from .divergence import Jet, divergence_form

_WIDTHS = Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) >= 2 and all(
    Interval(Integral, 2).is_satisfied_by(w) for w in v),
    "a list of half-widths in samples, >= 2 each: [time, axis 1, ...]")


class FieldWeakForm(Estimator):
    """Weak form over space-time test functions (see the module docstring).

    Args:
        widths: half-widths of the test functions in samples, ``[time, x(, y)]``; ``None``
            (default): chosen from the data at each fit, where the fields' spectra meet
            their noise (:mod:`discrepancy.pde.auto`).
        power: ``q`` of ``(1 - τ²)^q``; ``None``: ``max(8, 2 * derivative order + 2)``, so
            that every kernel vanishes smoothly at the support's edge.
        stride: grid points between neighbouring centres per spatial axis; ``None``: half
            the spatial half-width.
        noise_std: the fields' noise standard deviations, one per field, whose bias in
            polynomial terms is removed (:func:`unbiased`); ``None``: estimated from the
            data at each fit; ``0``: no correction.
    """

    _parameter_constraints = {"widths": [None, _WIDTHS], "power": [None, Interval(Integral, 2, 24)],
                              "stride": [None, Predicate(lambda v: isinstance(v, (list, tuple))
                                                         and all(Interval(Integral, 1)
                                                                 .is_satisfied_by(s) for s in v),
                                                         "a list of strides >= 1 per axis")],
                              "noise_std": [None, Interval(Real, 0, 0), Predicate(
                                  lambda v: isinstance(v, (list, tuple)) and all(
                                      Interval(Real, 0).is_satisfied_by(s) for s in v),
                                  "a list of standard deviations >= 0, one per field")]}

    def __init__(self, widths=None, *, power: int | None = None, stride=None,
                 noise_std=None):
        self.widths = widths
        self.power = power
        self.stride = stride
        self.noise_std = noise_std

    @property
    def data_driven(self) -> bool:
        """True when the widths are chosen from the data at each fit (``widths=None``)."""
        return self.widths is None

    @property
    def halo(self) -> int:
        """Time samples on each side of a centre that its test function covers (the time
        half-width ``widths[0]``); only defined once the widths are known."""
        return int(self.widths[0])

    @property
    def min_samples(self) -> int:
        """Fewest time samples a run needs: one whole test-function support, ``2 widths[0] + 1``."""
        return 2 * int(self.widths[0]) + 1

    def strides(self, grid) -> list[int]:
        """Grid points between centres per axis: ``stride``, or half the half-width but
        close enough for :data:`MIN_CENTRES` centres along the axis (few rows made the
        regression ill-conditioned on short non-periodic axes)."""
        if self.stride is not None:
            return [int(s) for s in self.stride]
        out = []
        for w, n, periodic in zip(self.widths[1:], grid.shape, grid.periodic, strict=True):
            room = n if periodic else max(1, n - 2 * int(w))
            out.append(max(1, min(int(w) // 2, room // MIN_CENTRES)))
        return out


#: fewest test-function centres wanted along an axis (when the axis allows them)
MIN_CENTRES = 16


def bump(width: int, power: int, order: int, step: float) -> np.ndarray:
    """Quadrature weights ``(2 width + 1,)`` of ``∂^order ψ`` for ``ψ`` of half-width
    ``width`` samples ``step`` apart (physical units: ``ψ((s - c) / (width step))``)."""
    coefficients = np.zeros(2 * power + 1)
    for k in range(power + 1):       # (1 - τ²)^q by the binomial theorem
        coefficients[2 * k] = comb(power, k) * (-1) ** k
    poly = np.polynomial.Polynomial(coefficients).deriv(order)
    tau = np.arange(-width, width + 1) / width
    return poly(tau) / (width * step) ** order * step


def centres(n: int, width: int, stride: int, periodic: bool) -> np.ndarray:
    """Grid indices of the test-function centres along one axis."""
    if periodic:
        return np.arange(0, n, stride)
    if n < 2 * width + 1:
        raise ShapeError(f"a test function of half-width {width} needs an axis of at least "
                         f"{2 * width + 1} points; this one has {n} (give smaller widths)")
    return np.arange(width, n - width, stride)


def window_matrix(n: int, weights: np.ndarray, index: np.ndarray,
                  periodic: bool) -> np.ndarray:
    """``(n, len(index))``: column ``k`` holds ``weights`` centred on grid point
    ``index[k]`` (wrapped on a periodic axis), so ``a @ W`` gives the window sums."""
    w = len(weights) // 2
    out = np.zeros((n, len(index)))
    rows = index[None, :] + np.arange(-w, w + 1)[:, None]
    cols = np.broadcast_to(np.arange(len(index)), rows.shape)
    np.add.at(out, ((rows % n) if periodic else rows, cols), np.broadcast_to(
        weights[:, None], rows.shape))
    return out


def integrate_space(a: np.ndarray, axis: int, weights: np.ndarray, index: np.ndarray,
                    periodic: bool) -> np.ndarray:
    """Window sums ``Σ_j weights[j] a[c - w + j]`` along ``axis`` at the centres ``index``
    (one matrix product: measured 100x faster than a gather per tap for wide windows)."""
    matrix = window_matrix(a.shape[axis], weights, index, periodic)
    return np.moveaxis(np.tensordot(a, matrix, axes=([axis], [0])), -1, axis)


def integrate_time(a: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Time window sums at every sample (axis 0); rows whose window leaves ``a`` are 0."""
    from scipy.signal import oaconvolve

    w, m = len(weights) // 2, a.shape[0]
    out = np.zeros_like(a)
    if m > 2 * w:
        shape = (len(weights),) + (1,) * (a.ndim - 1)
        out[w:m - w] = oaconvolve(a, weights[::-1].reshape(shape), mode="valid", axes=0)
    return out


@dataclass(frozen=True)
class WeakPlan:
    """Which integrals a fit needs and how the library's columns are made of them.

    Attributes:
        integrals: ``[(β, h)]``: integrate ``h`` (an expression of low-order jet
            variables) against ``∂^β φ``.
        columns: per library column, ``[(sign * coefficient, integral index)]``.
        prior: the same for each field's prior expression (``None``: pointwise prior).
        order: highest derivative among the ``h`` (what the data must be differentiated to).
    """

    integrals: list
    columns: list
    prior: list | None
    order: int
    cache: dict

    @classmethod
    def build(cls, expressions, prior_expressions, fields, coordinates,
              noise=None) -> WeakPlan:
        """The plan for library ``expressions`` and the prior's; ``noise``: the fields'
        noise standard deviations, whose bias in polynomial terms is removed
        (:func:`unbiased`)."""
        jet = Jet(fields, coordinates)
        integrals, index = [], {}

        def terms(expr):
            out = []
            for beta, h in divergence_form(expr, jet).items():
                if noise is not None:
                    h = unbiased(h, dict(zip(fields, noise, strict=True)))
                for part in sp.Add.make_args(h):
                    c, body = part.as_coeff_Mul()
                    key = (beta, body)
                    if key not in index:
                        index[key] = len(integrals)
                        integrals.append(key)
                    out.append(((-1) ** sum(beta) * float(c), index[key]))
            return out

        columns = [terms(e) for e in expressions]
        prior = None if prior_expressions is None else [terms(e) for e in prior_expressions]
        order = max((jet.order(h) for _, h in integrals), default=0)
        return cls(integrals, columns, prior, order, {})

    def evaluators(self, names, functions) -> list:
        """Numpy evaluators of every ``h`` on the jet variables ``names`` (cached)."""
        key = tuple(names)
        if key not in self.cache:
            self.cache[key] = [compile_numpy(h, names, functions) for _, h in self.integrals]
        return self.cache[key]


def unbiased(h: sp.Expr, noise: dict) -> sp.Expr:
    """``h`` with each monomial of the fields replaced by its unbiased counterpart under
    independent Gaussian noise of standard deviation ``noise[field]``: ``u^k`` becomes the
    scaled Hermite polynomial ``σ^k He_k(u / σ)`` (``u² - σ²``, ``u³ - 3 σ² u``), whose mean
    over the noise is ``u^k``. Terms with derivatives or other symbols are left alone (their
    noise is filtered, not white)."""
    from sympy.polys.orthopolys import hermite_prob_poly

    symbols = [s for s in h.free_symbols]
    if not symbols or any(s.name not in noise for s in symbols):
        return h
    poly = sp.Poly(h, *symbols)
    out = sp.S.Zero
    for powers, c in poly.terms():
        term = sp.Float(c) if not c.is_Rational else c
        for s, k in zip(symbols, powers, strict=True):
            sigma = float(noise[s.name])
            if k >= 2 and sigma > 0:
                x = sp.Dummy()
                term *= sp.expand(sigma ** k * hermite_prob_poly(k, x)).subs(x, s / sigma)
            else:
                term *= s ** k
        out += sp.expand(term)
    return sp.expand(out)


def weak_rows(form: FieldWeakForm, plan: WeakPlan, u, inputs, t, grid, jet_names, jet,
              functions, prior_values=None):
    """``(theta, y, signal)`` rows of one run piece (see the module docstring).

    ``jet`` ``(k, *shape, v)``: the variables ``jet_names`` on the snapshots (derivatives to
    ``plan.order``); ``prior_values``: a callable prior's ``N_m`` on them, or ``None``."""
    dt = float(t[1] - t[0])
    q = int(form.power)
    widths, strides = [int(w) for w in form.widths], form.strides(grid)
    index = [centres(n, w, s, p) for n, w, s, p in zip(grid.shape, widths[1:], strides,
                                                       grid.periodic, strict=True)]

    def in_space(values, beta):
        for axis, (w, b, h, p) in enumerate(zip(widths[1:], beta, grid.spacing, grid.periodic,
                                                strict=True)):
            values = integrate_space(values, axis + 1, bump(w, q, b, h), index[axis], p)
        return values

    def in_time(values, time_order=0):
        out = integrate_time(values, bump(widths[0], q, time_order, dt))
        return out.reshape(-1, values.shape[-1])

    zeros = (0,) * grid.ndim
    signal = -in_time(in_space(u, zeros), time_order=1)
    flat = jet.reshape(-1, jet.shape[-1])
    evaluators = plan.evaluators(jet_names, functions)
    # each term is reduced in space first (strided centres), so only reduced arrays pile up
    reduced = [in_space(np.broadcast_to(f(flat), flat.shape[:1]).reshape(
        *jet.shape[:-1], 1), beta) for f, (beta, _) in zip(evaluators, plan.integrals,
                                                            strict=True)]
    done = in_time(np.concatenate(reduced, axis=-1)) if reduced else np.zeros((len(signal), 0))
    values = list(done.T)
    theta = _combine(plan.columns, values, signal.shape[0])
    if plan.prior is not None:
        prior = _combine(plan.prior, values, signal.shape[0])
    elif prior_values is not None:
        prior = in_time(in_space(prior_values, zeros))
    else:
        prior = np.zeros_like(signal)
    return theta, signal - prior, signal


def _combine(recipes, values, rows: int) -> np.ndarray:
    out = np.zeros((rows, len(recipes)))
    for j, recipe in enumerate(recipes):
        for c, k in recipe:
            out[:, j] += c * values[k]
    return out
