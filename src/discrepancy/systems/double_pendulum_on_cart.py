"""Double pendulum on a cart whose acceleration is the input (paper Section IV.C).

State ``x = [phi1, phi2, s, dphi1, dphi2, ds]``: link angles (rad) measured from
upright (0 up, pi hanging), cart position ``s`` (m) and their rates; input
``u`` (m/s^2): the cart accelerates as ``s'' = gain u`` (``gain`` = 1 by default, a motor
gain to get wrong in a model). The equations are derived with sympy from the Lagrangian of
the two links on the moving base, with centres of mass at
``(s + a1 sin phi1, a1 cos phi1)`` and ``(s + l1 sin phi1 + a2 sin phi2,
l1 cos phi1 + a2 cos phi2)`` and viscous joint friction (Rayleigh function
``D = k1 dphi1^2 / 2 + k2 (dphi2 - dphi1)^2 / 2``).

The paper's flawed model adds ``sin(phi1)`` to ``(phi1)'`` and scales the
cart's acceleration to ``0.95 u``; the angle accelerations still see the true
``u``. Its discrepancy is therefore ``[-sin(phi1), 0, 0, 0, 0, 0.05 u]``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from functools import lru_cache, partial

import numpy as np
import sympy as sp

from ..errors import ParameterError, ShapeError, describe
from ..symbolic import compile_numpy, symbol
from .base import PAPER_TABLE_1, System, check_physical_parameters, scaled_parameters
from .mechanics import lagrange_equations, time_derivative

STATE_NAMES = ("phi1", "phi2", "s", "dphi1", "dphi2", "ds")
INPUT_NAMES = ("u",)


@dataclass(frozen=True)
class CartPendulumParameters:
    """Physical parameters, SI units; defaults are the paper's Table 1.

    ``m``: link masses (kg); ``a``: joint-to-centre-of-mass distances (m);
    ``I``: link inertias about their centres of mass (kg m^2); ``l``: link
    lengths (m); ``k``: viscous joint friction (N m s); ``g`` (m/s^2); ``gain``: cart
    acceleration per unit input (1: the input is the acceleration).
    """

    m1: float = PAPER_TABLE_1["m1"]
    m2: float = PAPER_TABLE_1["m2"]
    a1: float = PAPER_TABLE_1["a1"]
    a2: float = PAPER_TABLE_1["a2"]
    I1: float = PAPER_TABLE_1["I1"]
    I2: float = PAPER_TABLE_1["I2"]
    l1: float = PAPER_TABLE_1["l1"]
    l2: float = PAPER_TABLE_1["l1"]    # Table 1 lists 0.2667 m for both arms
    k1: float = PAPER_TABLE_1["k1"]
    k2: float = PAPER_TABLE_1["k2"]
    g: float = PAPER_TABLE_1["g"]
    gain: float = 1.0

    def __post_init__(self):
        check_physical_parameters(self)

    def scaled(self, factors) -> CartPendulumParameters:
        """A copy with each parameter multiplied by ``factors[name]`` (a mapping)."""
        return scaled_parameters(self, factors)


@lru_cache(maxsize=1)
def _derived():
    """Symbolic mass matrix ``M`` (2x2), right side ``b`` (2,) and energy, in parameter symbols."""
    p1, p2, s, d1, d2, ds = (symbol(n) for n in STATE_NAMES)
    u = symbol("u")
    par = {f.name: sp.Symbol(f.name, positive=True) for f in fields(CartPendulumParameters)}
    m1, m2, a1, a2, I1, I2, l1 = (par[k] for k in ("m1", "m2", "a1", "a2", "I1", "I2", "l1"))
    q, dq = [p1, p2, s], [d1, d2, ds]
    rate = partial(time_derivative, q=q, dq=dq)

    x1, y1 = s + a1 * sp.sin(p1), a1 * sp.cos(p1)
    x2, y2 = s + l1 * sp.sin(p1) + a2 * sp.sin(p2), l1 * sp.cos(p1) + a2 * sp.cos(p2)
    kinetic = (m1 * (rate(x1) ** 2 + rate(y1) ** 2) + m2 * (rate(x2) ** 2 + rate(y2) ** 2)
               + I1 * d1 ** 2 + I2 * d2 ** 2) / 2
    potential = par["g"] * (m1 * y1 + m2 * y2)
    rayleigh = (par["k1"] * d1 ** 2 + par["k2"] * (d2 - d1) ** 2) / 2
    _, mass, rest = lagrange_equations(kinetic, potential, q, dq, dissipation=rayleigh,
                                       driven={2: par["gain"] * u})
    return par, mass, rest, sp.expand(kinetic + potential)


def _cramer(m11, m12, m22, b1, b2):
    det = m11 * m22 - m12 * m12
    return (m22 * b1 - m12 * b2) / det, (m11 * b2 - m12 * b1) / det


class DoublePendulumOnCart(System):
    """Double pendulum on an acceleration-driven cart.

    Args:
        params: :class:`CartPendulumParameters` (paper's Table 1 by default).

    ``equations()`` / ``flawed_equations()`` give the exact sympy right-hand sides
    (used for CasADi export and as a sympy prior); ``rhs`` / ``flawed_model()``
    are their vectorised numpy forms.
    """

    state_names = STATE_NAMES
    input_names = INPUT_NAMES

    def __init__(self, params: CartPendulumParameters | None = None):
        self.params = params

    # -- symbolic -----------------------------------------------------------------------------
    def _values(self):
        par = _derived()[0]
        return {par[k]: sp.Float(v, 17) for k, v in asdict(self.parameters).items()}

    @property
    def parameters(self) -> CartPendulumParameters:
        """The parameters in use: ``params``, or the paper's Table 1."""
        p = self.params if self.params is not None else CartPendulumParameters()
        if not isinstance(p, CartPendulumParameters):
            raise ParameterError(f"params must be a CartPendulumParameters; got {describe(p)}")
        return p

    def _matrices(self):
        _, mass, rest, energy = _derived()
        values = self._values()
        return mass.subs(values), rest.subs(values), energy.subs(values)

    @staticmethod
    def parametric_equations():
        """``(states, inputs, parameters, rhs)`` with the parameters left as sympy symbols
        (named like the fields of :class:`CartPendulumParameters`); lets one compiled function
        serve many parameter sets (e.g. a robustness study)."""
        par, mass, rest, _ = _derived()
        states = [symbol(n) for n in STATE_NAMES]
        inputs = [symbol(n) for n in INPUT_NAMES]
        dd1, dd2 = _cramer(mass[0, 0], mass[0, 1], mass[1, 1], rest[0], rest[1])
        return states, inputs, list(par.values()), [*states[3:], dd1, dd2,
                                                    par["gain"] * inputs[0]]

    def equations(self):
        """``(states, inputs, rhs)``: sympy symbols named as ``state_names`` / ``input_names``
        and the 6 true right-hand side expressions (accelerations by Cramer's rule)."""
        states = [symbol(n) for n in STATE_NAMES]
        inputs = [symbol(n) for n in INPUT_NAMES]
        mass, rest, _ = self._matrices()
        dd1, dd2 = _cramer(mass[0, 0], mass[0, 1], mass[1, 1], rest[0], rest[1])
        gain = self.parameters.gain
        return states, inputs, [states[3], states[4], states[5], dd1, dd2,
                                inputs[0] if gain == 1 else sp.Float(gain, 17) * inputs[0]]

    def flawed_equations(self):
        """``(states, inputs, rhs)`` of the paper's flawed model: ``(phi1)' = dphi1 + sin(phi1)``
        and ``(ds)' = 0.95 u`` (0.95 ``gain u``), everything else as in :meth:`equations`."""
        states, inputs, rhs = self.equations()
        rhs = list(rhs)
        rhs[0] = rhs[0] + sp.sin(states[0])
        rhs[5] = sp.Float(0.95) * rhs[5]
        return states, inputs, rhs

    def discrepancy_equations(self):
        """The exact discrepancy ``true - flawed``: ``[-sin(phi1), 0, 0, 0, 0, 0.05 gain u]``."""
        states, _, rhs = self.equations()
        return [-sp.sin(states[0]), 0, 0, 0, 0, sp.Float(0.05) * rhs[5]]

    # -- numeric ------------------------------------------------------------------------------
    def _numeric(self):
        if getattr(self, "_compiled", None) is None or self._compiled[0] != self.params:
            mass, rest, energy = self._matrices()
            names = [*STATE_NAMES, *INPUT_NAMES]
            parts = [mass[0, 0], mass[0, 1], mass[1, 1], rest[0], rest[1]]
            self._compiled = (self.params, [compile_numpy(e, names) for e in parts],
                              compile_numpy(energy, names))
        return self._compiled[1], self._compiled[2]

    def _stack(self, x, u):
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[1] != 6:
            raise ShapeError(f"x must be (m, 6) [phi1, phi2, s, dphi1, dphi2, ds]; got "
                             f"{describe(x)}")
        if u is None:
            u = np.zeros((x.shape[0], 1))
        u = np.asarray(u, dtype=float)
        if u.ndim == 1 and u.shape[0] == x.shape[0]:
            u = u[:, None]
        if u.shape != (x.shape[0], 1):
            raise ShapeError(f"u must be ({x.shape[0]}, 1) to match x; got {describe(u)}")
        return x, u, np.hstack([x, u])

    def rhs(self, x, u=None):
        """True ``dx/dt`` ``(m, 6)`` for ``x`` ``(m, 6)`` and cart acceleration ``u`` ``(m, 1)``."""
        x, u, z = self._stack(x, u)
        parts, _ = self._numeric()
        dd1, dd2 = _cramer(*(f(z) for f in parts))
        return np.column_stack([x[:, 3], x[:, 4], x[:, 5], dd1, dd2,
                                self.parameters.gain * u[:, 0]])

    def flawed_model(self):
        """The paper's flawed model as a vectorised callable ``f_m(x, u) -> (m, 6)``."""
        def f_m(x, u=None):
            out = self.rhs(x, u)
            out[:, 0] += np.sin(np.asarray(x, dtype=float)[:, 0])
            out[:, 5] *= 0.95
            return out
        return f_m

    def energy(self, x):
        """``H = T + V`` (J) of the two links ``(m,)``; the cart's own mass is not modelled."""
        x, _, z = self._stack(x, None)
        return self._numeric()[1](z)

    def dissipated_power(self, x):
        """Power lost in the joints ``k1 dphi1^2 + k2 (dphi1 - dphi2)^2`` (W), ``(m,)``."""
        x, _, _ = self._stack(x, None)
        p = self.parameters
        return p.k1 * x[:, 3] ** 2 + p.k2 * (x[:, 3] - x[:, 4]) ** 2

    def points(self, x):
        """Cart, elbow and tip positions ``(m, 3, 2)`` (m) for drawing."""
        x, _, _ = self._stack(x, None)
        p = self.parameters
        cart = np.column_stack([x[:, 2], np.zeros(len(x))])
        elbow = cart + p.l1 * np.column_stack([np.sin(x[:, 0]), np.cos(x[:, 0])])
        tip = elbow + p.l2 * np.column_stack([np.sin(x[:, 1]), np.cos(x[:, 1])])
        return np.stack([cart, elbow, tip], axis=1)
