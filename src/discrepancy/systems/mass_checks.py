"""Checks of a mechanical system's kinetic energy and mass matrix, with the coordinate named.

A kinetic energy ``T`` must be positive for every motion: its mass matrix
``M = ∂²T/∂q̇²`` positive definite. :func:`check_kinetic` evaluates ``M`` at the origin's
neighbourhood and at random states and refuses, by name, a coordinate whose mass is not
positive (``T = -½ φ̇²``, a rate missing from ``T``) or a matrix that is not positive definite
there. :func:`solve_mass` solves ``M q̈ = b`` per sample and reports a singular or
non-finite ``M`` with the sample and state, instead of numpy's ``LinAlgError``.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp

from ..errors import DataError, ParameterError
from ..expression_tape import compile_numpy_many
from ..symbolic import symbol

#: random states ``M`` is checked at (positions and rates uniform in [-3, 3])
N_CHECKS = 16


def check_kinetic(kinetic: sp.Expr, coordinates: Sequence[str], rates: Sequence[str]) -> None:
    """Raise ParameterError naming the coordinate unless ``∂²T/∂q̇²`` is finite and positive
    definite at :data:`N_CHECKS` random states (positions and rates in [-3, 3])."""
    names = [*coordinates, *rates]
    mass = sp.hessian(kinetic, [symbol(n) for n in rates])
    k = len(rates)
    rng = np.random.default_rng(0)
    states = rng.uniform(-3, 3, (N_CHECKS, 2 * k))
    with np.errstate(all="ignore"):
        entries = compile_numpy_many([e for row in mass.tolist() for e in row], names)
        matrices = stack_mass(entries(states), k, len(states))
    for m, state in zip(matrices, states, strict=True):
        where = ", ".join(f"{n}={v:.3g}" for n, v in zip(names, state, strict=True))
        bad = [i for i in range(k) if not np.isfinite(m[i]).all()]
        if bad:
            raise ParameterError(f"kinetic: the mass of coordinate {coordinates[bad[0]]!r} "
                                 f"(row ∂²T/∂{rates[bad[0]]}∂q̇) is not finite at {where}")
        for i in range(k):
            if not m[i, i] > 0:
                raise ParameterError(
                    f"kinetic energy must be positive: the mass of coordinate "
                    f"{coordinates[i]!r} (∂²T/∂{rates[i]}²) is {m[i, i]:.3g} at {where}; T "
                    f"must be ½ q̇ᵀ M(q) q̇ with M positive definite")
        lowest = np.linalg.eigvalsh((m + m.T) / 2)
        if lowest.min() <= 1e-12 * np.abs(m).max():
            weakest = coordinates[int(np.argmax(np.abs(np.linalg.eigh(m)[1][:, 0])))]
            raise ParameterError(
                f"kinetic: the mass matrix M = ∂²T/∂q̇² is not positive definite at {where} "
                f"(smallest eigenvalue {lowest.min():.3g}, mostly along coordinate "
                f"{weakest!r}); T must be positive for every motion")


def stack_mass(values, k: int, m: int) -> np.ndarray:
    """``M`` ``(m, k, k)`` from the values of its entries in row-major order, each ``(m,)``
    or one number for every row."""
    return stack_columns(values[:k * k], m).reshape(m, k, k)


def stack_columns(values, m: int) -> np.ndarray:
    """``(m, len(values))`` from values that are each ``(m,)`` or one number for every row
    (only those are broadcast: ``np.broadcast_to`` costs more than the rest of a
    one-sample right-hand side's stacking, and an adaptive integrator makes hundreds of
    thousands of such calls)."""
    return np.stack([v if getattr(v, "shape", None) == (m,) else np.broadcast_to(v, (m,))
                     for v in values], axis=-1)


def solve_mass(matrix: np.ndarray, b: np.ndarray, x: np.ndarray, state_names) -> np.ndarray:
    """``q̈`` ``(m, k)`` from ``M q̈ = b`` per sample; DataError naming the first sample
    (and its state) where ``M`` is singular or not finite."""
    finite = np.isfinite(matrix).all(axis=(1, 2))
    singular = ~finite | (np.abs(np.linalg.det(np.where(finite[:, None, None], matrix, 1.0)))
                          <= 1e-300)
    if not singular.any():
        try:
            return np.linalg.solve(matrix, b[..., None])[..., 0]
        except np.linalg.LinAlgError:
            singular = np.array([np.linalg.matrix_rank(mi) < len(mi) for mi in matrix])
    row = int(np.flatnonzero(singular)[0])
    state = ", ".join(f"{n}={v:.4g}" for n, v in zip(state_names, x[row], strict=True))
    what = "not finite" if not finite[row] else "singular"
    raise DataError(f"the mass matrix M(q) is {what} at sample {row} ({state}): the "
                    "accelerations are undefined there")
