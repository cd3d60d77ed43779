"""Simulating a PDE by the method of lines: spectral on periodic grids, stiff-aware in time.

Space: derivatives on periodic axes are spectral (exact for band-limited fields), on other
axes finite differences of fourth order with one-sided stencils at the ends; there the
boundary values stay those of ``u0`` (``boundary="fixed"``, Dirichlet) unless
``boundary="free"``.

Time, ``method="etdrk4"`` (the default on periodic grids when every term is symbolic): the
right-hand side is split into its linear constant-coefficient part ``L`` (terms ``c ∂^α u``
of each field's own equation, diagonal in Fourier space) and the rest ``N``; ``L`` is
integrated exactly and ``N`` by the fourth-order exponential Runge-Kutta scheme of Cox &
Matthews with the contour-integral coefficients of Kassam & Trefethen (2005). Why: a fourth
derivative (Kuramoto-Sivashinsky) makes explicit methods need steps ~ dx⁴ and implicit ones
a dense Jacobian solve per step; ETDRK4 takes steps set by the nonlinear dynamics alone,
with no linear solve. Step doubling controls the error: each sample interval is taken with
``s`` and ``2 s`` steps, the finer result kept when both agree to ``rtol`` (else ``s``
doubles; it never shrinks back, so the step follows the hardest part of the run). Written
by hand: scipy has no exponential integrator. Otherwise (a callable prior, a non-periodic
axis) scipy's ``solve_ivp`` with ``method`` (default ``"BDF"``, for stiff diffusion)
integrates the semi-discrete system.
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..errors import ParameterError, SimulationError
from ..libraries.pde import parse_derivative
from .variables import FieldVariables

#: points on the contour for the ETDRK4 coefficients (Kassam & Trefethen use 32)
CONTOUR_POINTS = 64
MAX_HALVINGS = 12


def linear_part(expressions, fields, coordinates) -> list[dict[tuple[int, ...], float]]:
    """Per field ``i``, ``{α: c}`` for the terms ``c ∂^α u_i`` (α may be 0) of its own
    equation with constant numeric ``c``."""
    out = []
    for i, expr in enumerate(expressions):
        terms = {}
        for term in sp.Add.make_args(sp.expand(expr)):
            c, body = term.as_coeff_Mul()
            if not body.is_Symbol:
                continue
            if body.name == fields[i]:
                alpha = (0,) * len(coordinates)
            else:
                found = parse_derivative(body.name, fields, coordinates)
                if found is None or found[0] != fields[i]:
                    continue
                alpha = found[1]
            terms[alpha] = terms.get(alpha, 0.0) + float(c)
        out.append(terms)
    return out


def fourier_symbols(grid, terms) -> np.ndarray:
    """``L(k)`` ``(*rfft shape)`` of one field's linear terms on a periodic grid."""
    ks = [2 * np.pi * np.fft.fftfreq(n, d=h) for n, h in zip(grid.shape, grid.spacing,
                                                            strict=True)]
    ks[-1] = 2 * np.pi * np.fft.rfftfreq(grid.shape[-1], d=grid.spacing[-1])
    mesh = np.meshgrid(*ks, indexing="ij")
    out = np.zeros(mesh[0].shape, dtype=complex)
    for alpha, c in terms.items():
        factor = np.ones_like(out)
        for axis, (k, a) in enumerate(zip(mesh, alpha, strict=True)):
            ik = (1j * k) ** a
            n = grid.shape[axis]
            if a % 2 == 1 and n % 2 == 0:   # Nyquist mode: no real odd derivative
                ik = np.where(np.isclose(np.abs(k), np.pi / grid.spacing[axis]), 0, ik)
            factor = factor * ik
        out += c * factor
    return out


class ETDRK4:
    """Exponential time differencing RK4 on the Fourier modes of each field."""

    def __init__(self, L: np.ndarray, h: float):
        self.h = h
        self.E, self.E2 = np.exp(h * L), np.exp(h * L / 2)
        # the whole circle: L may be complex (odd derivatives), so no real-part shortcut
        r = np.exp(2j * np.pi * (np.arange(1, CONTOUR_POINTS + 1) - 0.5) / CONTOUR_POINTS)
        LR = h * L[..., None] + r
        mean = lambda a: a.mean(axis=-1)  # noqa: E731
        self.Q = h * mean((np.exp(LR / 2) - 1) / LR)
        self.f1 = h * mean((-4 - LR + np.exp(LR) * (4 - 3 * LR + LR ** 2)) / LR ** 3)
        self.f2 = h * mean((2 + LR + np.exp(LR) * (LR - 2)) / LR ** 3)
        self.f3 = h * mean((-4 - 3 * LR - LR ** 2 + np.exp(LR) * (4 - LR)) / LR ** 3)

    def step(self, v, t, N):
        """One step of the Fourier modes ``v`` from time ``t``; ``N(v, t)`` gives the
        nonlinear part's modes."""
        h = self.h
        Nv = N(v, t)
        a = self.E2 * v + self.Q * Nv
        Na = N(a, t + h / 2)
        b = self.E2 * v + self.Q * Na
        Nb = N(b, t + h / 2)
        c = self.E2 * a + self.Q * (2 * Nb - Nv)
        Nc = N(c, t + h)
        return self.E * v + Nv * self.f1 + 2 * (Na + Nb) * self.f2 + Nc * self.f3


class SpectralJet:
    """The jet variables of fields on a periodic grid straight from their Fourier modes
    (the hot path of ETDRK4: one inverse transform per derivative). ``used``: the names
    the expressions read (None: all); a derivative order none of them reads is left zero
    instead of transformed."""

    def __init__(self, grid, variables: FieldVariables, used=None):
        self.grid = grid
        orders = {}
        for alpha, _, name in variables.derivatives:
            orders[alpha] = orders.get(alpha, False) or used is None or name in used
        self.multipliers = [fourier_symbols(grid, {alpha: 1.0})[..., None] if read else None
                            for alpha, read in orders.items()]
        self.axes = tuple(range(grid.ndim))
        self.zero = np.zeros((*grid.shape, len(variables.fields)))   # an order not read

    def __call__(self, v: np.ndarray) -> np.ndarray:
        """``(*grid.shape, n * (1 + derivatives))`` from modes ``v`` ``(*rfft shape, n)``."""
        back = [self.zero if m is None else
                np.fft.irfftn(m * v, s=self.grid.shape, axes=self.axes)
                for m in [1.0, *self.multipliers]]
        return np.concatenate(back, axis=-1)


def run_etdrk4(N, L, u0, t, grid, *, rtol: float):
    """Fields at times ``t`` ``(k, *shape, n)`` from ``u0`` under ``u_t = L u + N(u)``;
    ``N(v, time)`` gives the modes of the nonlinear part from the modes ``v``."""
    axes = tuple(range(grid.ndim))
    back = lambda v: np.fft.irfftn(v, s=grid.shape, axes=axes)  # noqa: E731

    schemes: dict = {}

    def advance(v, t0, dt, steps):
        key = (dt, steps)
        if key not in schemes:
            schemes[key] = ETDRK4(L, dt / steps)
        scheme = schemes[key]
        for s in range(steps):
            v = scheme.step(v, t0 + s * dt / steps, N)
        return v

    out = np.empty((len(t), *u0.shape))
    out[0], v, steps = u0, np.fft.rfftn(u0, axes=axes), 1
    for i in range(1, len(t)):
        v, steps = _interval(advance, v, t[i - 1], float(t[i] - t[i - 1]), steps, rtol)
        out[i] = back(v) if v is not None else np.nan
        if not np.all(np.isfinite(out[i])):
            raise SimulationError(f"the simulation blew up before t = {t[i]:.6g}",
                                  time=float(t[i - 1]), state=out[i - 1],
                                  partial=out[:i], times=t[:i])
    return out


def _interval(advance, v, t0, dt, steps, rtol):
    """Modes after one sample interval and the steps used: ``2 * steps`` steps, accepted
    when ``steps`` steps agree with them to ``rtol`` (step doubling), else more steps."""
    for _ in range(MAX_HALVINGS):
        fine, coarse = advance(v, t0, dt, 2 * steps), advance(v, t0, dt, steps)
        if np.max(np.abs(fine - coarse)) <= rtol * max(np.max(np.abs(fine)), 1e-300):
            return fine, steps
        steps *= 2
    return None, steps      # no step size reaches rtol: blowing up


def jacobian_sparsity(grid, n_fields: int, order: int):
    """Which values each point's derivative depends on, for ``solve_ivp``'s finite-difference
    Jacobian: every field within the reach of the 4th-order stencils (``order + 3`` points,
    one-sided ends included) along non-periodic axes, the whole of periodic (spectral) ones."""
    from scipy import sparse

    reach = order + 3
    pattern = sparse.csr_matrix(np.ones((1, 1)))
    for n, periodic in zip(grid.shape, grid.periodic, strict=True):
        i = np.arange(n)
        axis = np.ones((n, n)) if periodic else (np.abs(i[:, None] - i[None, :]) <= reach)
        pattern = sparse.kron(pattern, sparse.csr_matrix(axis.astype(float)), format="csr")
    return sparse.kron(pattern, sparse.csr_matrix(np.ones((n_fields, n_fields))), format="csr")


def run_solve_ivp(rhs, u0, t, *, method: str, rtol: float, atol: float, fixed=None,
                  sparsity=None):
    """The semi-discrete system with scipy's ``solve_ivp``; ``fixed``: a boolean mask of
    points held at their initial values; ``sparsity``: the Jacobian's pattern (BDF, Radau)."""
    from scipy.integrate import solve_ivp

    shape = u0.shape

    def f(time, y):
        du = rhs(y.reshape(shape), time)
        if fixed is not None:
            du = np.where(fixed, 0.0, du)
        return du.ravel()

    options = {} if sparsity is None else {"jac_sparsity": sparsity}
    sol = solve_ivp(f, (t[0], t[-1]), u0.ravel(), t_eval=t, method=method, rtol=rtol,
                    atol=atol, **options)
    if not sol.success or sol.y.shape[1] != len(t):
        k = sol.y.shape[1]
        raise SimulationError(f"solve_ivp ({method}) stopped at t = {sol.t[-1] if k else t[0]:.6g}"
                              f": {sol.message}", time=float(sol.t[-1] if k else t[0]),
                              state=sol.y[:, -1].reshape(shape) if k else u0,
                              partial=sol.y.T.reshape(k, *shape), times=sol.t)
    return sol.y.T.reshape(len(t), *shape)


def boundary_mask(grid, n_fields: int) -> np.ndarray:
    """``(*shape, n)``: points on the ends of non-periodic axes (held fixed)."""
    mask = np.zeros((*grid.shape, n_fields), bool)
    for axis, periodic in enumerate(grid.periodic):
        if not periodic:
            index = [slice(None)] * (grid.ndim + 1)
            index[axis] = [0, grid.shape[axis] - 1]
            mask[tuple(index)] = True
    return mask


def simulation_methods(grid):
    """Spatial methods for simulating: spectral on periodic axes, 4th-order FD elsewhere."""
    from ..differentiation.spatial import SpatialFiniteDifference, SpatialSpectral

    return tuple(SpatialSpectral() if p else SpatialFiniteDifference(4) for p in grid.periodic)


def check_method(method: str, symbolic: bool, grid) -> str:
    """The time integrator for ``method`` (``"auto"`` resolved), or ParameterError."""
    valid = ("auto", "etdrk4", "RK45", "RK23", "DOP853", "BDF", "Radau", "LSODA")
    if method not in valid:
        raise ParameterError(f"method must be one of {', '.join(valid)}; got {method!r}")
    periodic = all(grid.periodic)
    if method == "etdrk4" and not (periodic and symbolic):
        raise ParameterError("method='etdrk4' needs a periodic grid and a symbolic prior (the "
                             "linear part is read from the expressions); use 'BDF'")
    if method == "auto":
        return "etdrk4" if periodic and symbolic else "BDF"
    return method
