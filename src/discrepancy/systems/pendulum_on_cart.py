"""Single pendulum on an acceleration-driven cart, with a flawed prior to learn against.

State ``x = [phi, s, dphi, ds]``: the link angle (rad) from upright (0 up, pi hanging), the
cart position ``s`` (m) and their rates; input ``u`` (m/s^2), the cart accelerating as
``s'' = gain u``. The equation of motion is derived with sympy
(:func:`~discrepancy.systems.mechanics.lagrange_equations`) from the Lagrangian of a link
with its centre of mass at ``(s + a sin phi, a cos phi)`` and viscous joint friction
(Rayleigh function ``D = k dphi^2 / 2``):
``(I + m a^2) phi'' = m a (g sin phi - gain u cos phi) - k dphi``.

The flawed prior (:meth:`PendulumOnCart.flawed_equations`) has no joint friction and
believes the motor ``motor_error`` (50 %) stronger than it is, so its exact discrepancy
is sparse in ``[dphi, cos(phi) u, u]``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from functools import lru_cache, partial

import numpy as np
import sympy as sp

from ..errors import ParameterError, ShapeError, describe
from ..symbolic import compile_numpy, symbol
from .base import PAPER_TABLE_1, System, check_physical_parameters, scaled_parameters
from .mechanics import lagrange_equations, time_derivative

STATE_NAMES = ("phi", "s", "dphi", "ds")
INPUT_NAMES = ("u",)


@dataclass(frozen=True)
class PendulumOnCartParameters:
    """Physical parameters, SI units; defaults: the first link of the paper's Table 1.

    ``m``: link mass (kg); ``a``: joint-to-centre-of-mass distance (m); ``I``: inertia
    about the centre of mass (kg m^2); ``l``: link length (m, for drawing); ``k``: viscous
    joint friction (N m s); ``g`` (m/s^2); ``gain``: cart acceleration per unit input.
    """

    m: float = PAPER_TABLE_1["m1"]
    a: float = PAPER_TABLE_1["a1"]
    I: float = PAPER_TABLE_1["I1"]
    l: float = PAPER_TABLE_1["l1"]
    k: float = PAPER_TABLE_1["k1"]
    g: float = PAPER_TABLE_1["g"]
    gain: float = 1.0

    def __post_init__(self):
        check_physical_parameters(self, may_be_zero=("k",))

    def scaled(self, factors) -> PendulumOnCartParameters:
        """A copy with each parameter multiplied by ``factors[name]`` (a mapping)."""
        return scaled_parameters(self, factors)


@lru_cache(maxsize=1)
def _derived():
    """Parameter symbols and the symbolic right-hand side ``[ds... , phi'', gain u]``."""
    phi, s, dphi, ds = (symbol(n) for n in STATE_NAMES)
    u = symbol("u")
    par = {f.name: sp.Symbol(f.name, positive=True) for f in fields(PendulumOnCartParameters)}
    m, a, inertia = par["m"], par["a"], par["I"]
    q, dq = [phi, s], [dphi, ds]
    rate = partial(time_derivative, q=q, dq=dq)

    x, y = s + a * sp.sin(phi), a * sp.cos(phi)
    kinetic = (m * (rate(x) ** 2 + rate(y) ** 2) + inertia * dphi ** 2) / 2
    potential = par["g"] * m * y
    _, mass, rest = lagrange_equations(kinetic, potential, q, dq,
                                       dissipation=par["k"] * dphi ** 2 / 2,
                                       driven={1: par["gain"] * u})
    accel = sp.simplify(rest[0] / mass[0, 0])
    return par, [dphi, ds, accel, par["gain"] * u]


class PendulumOnCart(System):
    """Single pendulum on an acceleration-driven cart.

    Args:
        params: :class:`PendulumOnCartParameters` (the first link of Table 1 by default).
        motor_error: how much stronger than the truth the flawed prior's motor gain is
            (0.5: the prior's cart accelerates 50 % more per unit input).
    """

    state_names = STATE_NAMES
    input_names = INPUT_NAMES

    def __init__(self, params: PendulumOnCartParameters | None = None, *,
                 motor_error: float = 0.5):
        self.params = params
        self.motor_error = motor_error

    @property
    def parameters(self) -> PendulumOnCartParameters:
        """The parameters in use: ``params``, or the paper's Table 1."""
        p = self.params if self.params is not None else PendulumOnCartParameters()
        if not isinstance(p, PendulumOnCartParameters):
            raise ParameterError(f"params must be a PendulumOnCartParameters; got {describe(p)}")
        return p

    @staticmethod
    def parametric_equations():
        """``(states, inputs, parameters, rhs)`` with the parameters as sympy symbols."""
        par, rhs = _derived()
        return ([symbol(n) for n in STATE_NAMES], [symbol(n) for n in INPUT_NAMES],
                list(par.values()), list(rhs))

    def equations(self, params: PendulumOnCartParameters | None = None):
        """``(states, inputs, rhs)``: the true right-hand sides as sympy expressions."""
        par, rhs = _derived()
        values = asdict(params if params is not None else self.parameters)
        subs = {par[k]: sp.Float(v, 17) for k, v in values.items()}
        return ([symbol(n) for n in STATE_NAMES], [symbol(n) for n in INPUT_NAMES],
                [sp.expand(e.subs(subs)) if e.free_symbols & set(subs) else e for e in rhs])

    def flawed_equations(self):
        """The prior: no joint friction, motor gain ``1 + motor_error`` times the truth."""
        p = self.parameters
        if not (np.isfinite(self.motor_error) and self.motor_error > -1):
            raise ParameterError(f"motor_error must be a finite number > -1; got "
                                 f"{self.motor_error!r}")
        return self.equations(replace(p, k=0.0, gain=p.gain * (1 + self.motor_error)))

    def discrepancy_equations(self):
        """The exact discrepancy ``true - flawed`` (sympy, one per state)."""
        true, flawed = self.equations()[2], self.flawed_equations()[2]
        return [sp.expand(a - b) for a, b in zip(true, flawed, strict=True)]

    def _compiled(self):
        key = asdict(self.parameters)
        if getattr(self, "_key", None) != key:
            names = [*STATE_NAMES, *INPUT_NAMES]
            self._key, self._f = key, [compile_numpy(e, names) for e in self.equations()[2]]
        return self._f

    def rhs(self, x, u=None):
        """True ``dx/dt`` ``(m, 4)`` for ``x`` ``(m, 4)`` and ``u`` ``(m, 1)``."""
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[1] != 4:
            raise ShapeError(f"x must be (m, 4) [phi, s, dphi, ds]; got {describe(x)}")
        u = np.zeros((len(x), 1)) if u is None else np.asarray(u, dtype=float).reshape(-1, 1)
        if len(u) != len(x):
            raise ShapeError(f"u must be ({len(x)}, 1) to match x; got {describe(u)}")
        z = np.hstack([x, u])
        return np.column_stack([f(z) for f in self._compiled()])

    def energy(self, x):
        """``H = T + V`` (J) of the link for a resting cart, ``(m,)``."""
        x = np.asarray(x, dtype=float)
        p = self.parameters
        kinetic = (p.m * p.a ** 2 + p.I) * x[:, 2] ** 2 / 2 \
            + p.m * (x[:, 3] ** 2 / 2 + p.a * np.cos(x[:, 0]) * x[:, 2] * x[:, 3])
        return kinetic + p.m * p.g * p.a * np.cos(x[:, 0])

    def points(self, x):
        """Cart and tip positions ``(m, 2, 2)`` (m) for drawing."""
        x = np.asarray(x, dtype=float)
        cart = np.column_stack([x[:, 1], np.zeros(len(x))])
        tip = cart + self.parameters.l * np.column_stack([np.sin(x[:, 0]), np.cos(x[:, 0])])
        return np.stack([cart, tip], axis=1)
