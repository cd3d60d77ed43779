"""Kinetic energies that are not positive are refused naming the coordinate; a mass matrix
singular at a sample is reported with the sample, not as numpy's LinAlgError."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from discrepancy.errors import DataError, ParameterError
from discrepancy.systems.lagrangian import LagrangianSystem

phi, dphi, x, dx = sp.symbols("phi dphi x dx")


@pytest.mark.parametrize("kinetic, coordinates, pattern", [
    (-dphi ** 2 / 2, ["phi"], r"mass of coordinate 'phi' \(∂²T/∂dphi²\) is -1"),
    (dx ** 2 / 2, ["x", "phi"], r"mass of coordinate 'phi' \(∂²T/∂dphi²\) is 0"),
    ((dx ** 2 + dphi ** 2) / 2 + 2 * dx * dphi, ["x", "phi"],
     r"not positive definite .*smallest eigenvalue -1"),
    (dphi ** 2 / (2 * sp.cos(phi) - 3), ["phi"], r"mass of coordinate 'phi'"),
])
def test_kinetic_energy_that_is_not_positive_is_refused_by_coordinate(kinetic, coordinates,
                                                                      pattern):
    with pytest.raises(ParameterError, match=pattern):
        LagrangianSystem(kinetic, -sp.cos(phi), coordinates)


def test_a_valid_cart_pendulum_gives_its_closed_form_accelerations():
    """M = [[2, cos φ], [cos φ, 1]], b = [φ̇² sin φ, -g sin φ]: solved by hand."""
    g = 9.81
    system = LagrangianSystem((2 * dx ** 2 + dphi ** 2) / 2 + dx * dphi * sp.cos(phi),
                              -g * sp.cos(phi), ["x", "phi"])
    state = np.array([0.0, 0.4, 0.0, 0.7])
    c, s = np.cos(0.4), np.sin(0.4)
    expected = np.linalg.solve([[2, c], [c, 1]], [0.7 ** 2 * s, -g * s])
    np.testing.assert_allclose(system.rhs(state)[0, 2:], expected, rtol=1e-12)


def test_a_mass_matrix_singular_at_a_sample_is_named():
    """M = [[1, cos φ], [cos φ, 1]] is positive definite except where cos φ = ±1."""
    system = LagrangianSystem((dx ** 2 + dphi ** 2) / 2 + dx * dphi * sp.cos(phi),
                              -sp.cos(phi), ["x", "phi"])
    assert np.all(np.isfinite(system.rhs([0.0, 0.5, 0.0, 0.0])))
    with pytest.raises(DataError, match=r"mass matrix M\(q\) is singular at sample 1 "
                                        r"\(x=0, phi=0, dx=0, dphi=0\)"):
        system.rhs(np.array([[0.0, 0.5, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]]))
