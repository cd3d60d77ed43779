"""Mounted double pendulum (cart locked) with viscous joint friction, paper Section IV.B.

State ``x = [phi1, phi2, dphi1, dphi2]`` (rad, rad/s); both angles are absolute and
measured from the upright, so ``phi = pi`` hangs down. The energy is the paper's
eqs. (29)-(35): centres of mass at ``x1 = a1 sin phi1``, ``y1 = a1 cos phi1``,
``x2 = l1 sin phi1 + a2 sin phi2``, ``y2 = l1 cos phi1 + a2 cos phi2``,
``T = m1 v1^2/2 + m2 v2^2/2 + (I1 dphi1^2 + I2 dphi2^2)/2`` and ``V = g (m1 y1 + m2 y2)``.
Joint friction enters through the Rayleigh function
``D = k1 dphi1^2 / 2 + k2 (dphi1 - dphi2)^2 / 2``; the equations of motion are derived
from ``T``, ``V`` and ``D`` with sympy (:func:`~discrepancy.systems.mechanics.lagrange_equations`).
"""
from __future__ import annotations

from dataclasses import astuple, dataclass
from functools import cache

import numpy as np
import sympy as sp

from ..errors import DataError, ParameterError, ShapeError
from ..expression_tape import compile_numpy_many
from ..symbolic import compile_numpy, symbol
from .base import PAPER_TABLE_1, System, check_physical_parameters
from .mechanics import lagrange_equations

STATE_NAMES = ("phi1", "phi2", "dphi1", "dphi2")
PARAMETER_ORDER = ("m1", "m2", "a1", "a2", "l1", "I1", "I2", "k1", "k2", "g")


@dataclass(frozen=True)
class DoublePendulumParameters:
    """Physical parameters; defaults are the paper's Table 1 (SI units).

    Attributes:
        m1, m2: arm masses (kg).
        a1, a2: pivot-to-centre-of-mass distances (m).
        l1: length of the first arm, pivot to pivot (m).
        I1, I2: inertias about the centres of mass (kg m^2).
        k1, k2: viscous friction of joint 1 and joint 2 (N m s / rad).
        g: gravity (m/s^2).
    """

    m1: float = PAPER_TABLE_1["m1"]
    m2: float = PAPER_TABLE_1["m2"]
    a1: float = PAPER_TABLE_1["a1"]
    a2: float = PAPER_TABLE_1["a2"]
    l1: float = PAPER_TABLE_1["l1"]
    I1: float = PAPER_TABLE_1["I1"]
    I2: float = PAPER_TABLE_1["I2"]
    k1: float = PAPER_TABLE_1["k1"]
    k2: float = PAPER_TABLE_1["k2"]
    g: float = PAPER_TABLE_1["g"]

    def __post_init__(self):
        check_physical_parameters(self)

    @classmethod
    def from_array(cls, values) -> DoublePendulumParameters:
        """From ``[m1 m2 a1 a2 l1 I1 I2 k1 k2 g]`` (the MultiArm-Pendulum file's order)."""
        arr = np.asarray(values, dtype=float).ravel()
        if arr.shape != (len(PARAMETER_ORDER),):
            raise ShapeError(f"parameter array must hold {len(PARAMETER_ORDER)} values "
                             f"[{' '.join(PARAMETER_ORDER)}]; got {arr.shape[0]}")
        return cls(**dict(zip(PARAMETER_ORDER, arr.tolist(), strict=True)))

    @classmethod
    def from_mat(cls, path, *, variable: str = "EstimatedParameters") -> DoublePendulumParameters:
        """From a MATLAB file holding ``variable`` = ``[m1 m2 a1 a2 l1 I1 I2 k1 k2 g]``,
        e.g. ``EstimatedParameters_DoublePendulum.mat`` of the MultiArm-Pendulum rig."""
        from ..data.io import read_mat

        contents = read_mat(path, what="parameter file")
        if variable not in contents:
            found = list(contents)
            raise DataError(f"{str(path)!r} has no variable {variable!r}; found {found}")
        return cls.from_array(contents[variable])

    def as_dict(self) -> dict[str, float]:
        """``{name: value}`` in the order of the model's parameter vector."""
        return dict(zip(PARAMETER_ORDER, astuple(self), strict=True))


def _centres(q):
    """``[(mass, x, y)]`` of the two centres of mass (``y`` up) for angle functions ``q``."""
    m1, m2, a1, a2, l1 = (symbol(n) for n in PARAMETER_ORDER[:5])
    return [(m1, a1 * sp.sin(q[0]), a1 * sp.cos(q[0])),
            (m2, l1 * sp.sin(q[0]) + a2 * sp.sin(q[1]), l1 * sp.cos(q[0]) + a2 * sp.cos(q[1]))]


@cache
def _symbolic_model():
    """Energy, dissipation and equations of motion with symbolic parameters (derived once)."""
    phi1, phi2, dphi1, dphi2 = (symbol(n) for n in STATE_NAMES)
    m1, m2, _, _, _, I1, I2, k1, k2, g = (symbol(n) for n in PARAMETER_ORDER)
    t = sp.Symbol("t", real=True)
    q = [sp.Function("q1")(t), sp.Function("q2")(t)]
    (_, x1, y1), (_, x2, y2) = _centres(q)
    speed2 = [sp.diff(x1, t) ** 2 + sp.diff(y1, t) ** 2, sp.diff(x2, t) ** 2 + sp.diff(y2, t) ** 2]
    kinetic = (m1 * speed2[0] + m2 * speed2[1]) / 2 \
        + (I1 * sp.diff(q[0], t) ** 2 + I2 * sp.diff(q[1], t) ** 2) / 2
    to_state = {sp.diff(q[0], t): dphi1, sp.diff(q[1], t): dphi2}
    kinetic = sp.simplify(kinetic.subs(to_state).subs({q[0]: phi1, q[1]: phi2}))
    potential = g * (m1 * y1 + m2 * y2).subs({q[0]: phi1, q[1]: phi2})
    dissipation = k1 * dphi1 ** 2 / 2 + k2 * (dphi1 - dphi2) ** 2 / 2
    _, mass, rest = lagrange_equations(kinetic, potential, [phi1, phi2], [dphi1, dphi2],
                                       dissipation=dissipation)
    return kinetic, potential, dissipation, mass, rest


@cache
def _symbolic_pivot_force():
    """``[Fx, Fy]``: force of the pivot on the pendulum (N), ``y`` up, from the second time
    derivatives of the centres of mass: ``F = m1 r1'' + m2 r2'' + (m1 + m2) g e_y``. In the
    symbols of the state and of the angular accelerations ``ddphi1``, ``ddphi2``."""
    phi1, phi2, dphi1, dphi2 = (symbol(n) for n in STATE_NAMES)
    dd = [symbol("ddphi1"), symbol("ddphi2")]
    m1, m2, *_, g = (symbol(n) for n in PARAMETER_ORDER)
    t = sp.Symbol("t", real=True)
    q = [sp.Function("q1")(t), sp.Function("q2")(t)]
    centres = _centres(q)
    to_state = {sp.diff(q[i], t, 2): dd[i] for i in range(2)}
    to_state |= {sp.diff(q[0], t): dphi1, sp.diff(q[1], t): dphi2}
    fx = sum(m * sp.diff(x, t, 2) for m, x, _ in centres)
    fy = sum(m * sp.diff(y, t, 2) for m, _, y in centres) + (m1 + m2) * g
    return [sp.expand(f.subs(to_state).subs({q[0]: phi1, q[1]: phi2})) for f in (fx, fy)]


@cache
def _paper_parameters() -> DoublePendulumParameters:
    """The default parameters, built (and checked) once: they are frozen."""
    return DoublePendulumParameters()


class DoublePendulum(System):
    """Mounted double pendulum with viscous joint friction (true system of Section IV.B).

    Args:
        params: a :class:`DoublePendulumParameters` (default: the paper's Table 1).

    ``energy`` is the conservative model energy ``H_m = T + V`` (J); ``rhs`` includes the
    friction torques ``k1 dphi1`` (joint 1) and ``k2 (dphi1 - dphi2)`` (joint 2), so
    ``dH_m/dt = -(k1 dphi1^2 + k2 (dphi1 - dphi2)^2)`` along trajectories.
    """

    state_names = STATE_NAMES
    input_names = ()

    def __init__(self, params: DoublePendulumParameters | None = None):
        self.params = params

    @property
    def parameters(self) -> DoublePendulumParameters:
        """The parameters in use: ``params``, or the paper's Table 1."""
        p = self.params if self.params is not None else _paper_parameters()
        if not isinstance(p, DoublePendulumParameters):
            raise ParameterError(f"params must be DoublePendulumParameters; got {type(p).__name__}")
        return p

    def _numbers(self) -> dict:
        return {symbol(k): v for k, v in self.parameters.as_dict().items()}

    def _compiled(self):
        """``(kinetic, potential, rhs_terms)`` compiled for these parameters: ``T``, ``V``
        and (on one tape, their shared sines and cosines once per call) M's entries and b."""
        # frozen parameters compare by value (building a dict of symbols as the key cost most
        # of a right-hand side's call)
        key = self.parameters
        if getattr(self, "_cache_key", None) != key:
            kinetic, potential, _, mass, rest = _symbolic_model()
            subs = self._numbers()
            exprs = [e.subs(subs) for e in (kinetic, potential, mass[0, 0], mass[0, 1],
                                            mass[1, 1], rest[0], rest[1])]
            self._functions = (compile_numpy(exprs[0], STATE_NAMES),
                               compile_numpy(exprs[1], STATE_NAMES),
                               compile_numpy_many(exprs[2:], STATE_NAMES))
            self._cache_key = key
        return self._functions

    def _state(self, x) -> np.ndarray:
        arr = np.asarray(x, dtype=float)
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != 4:
            raise ShapeError(f"x must be (m, 4) = [phi1, phi2, dphi1, dphi2]; "
                             f"got shape {arr.shape}")
        return arr

    def kinetic_energy(self, x) -> np.ndarray:
        """``T`` (J), shape ``(m,)``."""
        return self._compiled()[0](self._state(x))

    def energy(self, x) -> np.ndarray:
        """Conservative model energy ``H_m = T + V`` (J), shape ``(m,)``."""
        x = self._state(x)
        f = self._compiled()
        return f[0](x) + f[1](x)

    def dissipated_power(self, x) -> np.ndarray:
        """Power lost to joint friction ``k1 dphi1^2 + k2 (dphi1 - dphi2)^2`` (W), ``(m,)``."""
        x = self._state(x)
        p = self.parameters
        return p.k1 * x[:, 2] ** 2 + p.k2 * (x[:, 2] - x[:, 3]) ** 2

    def pivot_force(self, x, *, friction: bool = False) -> np.ndarray:
        """Force of the pivot on the pendulum ``[Fx, Fy]`` (N, ``Fy`` up), shape ``(m, 2)``.

        The centres of mass accelerate as the equations of motion say (conservative model
        unless ``friction``); at rest hanging down ``Fy = (m1 + m2) g``. The mount feels the
        opposite force: its dynamic part is what shakes the table under the rig.
        """
        x = self._state(x)
        key = self.parameters
        if getattr(self, "_pivot_key", None) != key:
            subs = self._numbers()
            names = (*STATE_NAMES, "ddphi1", "ddphi2")
            self._pivot_key = key
            self._pivot = [compile_numpy(f.subs(subs), names) for f in _symbolic_pivot_force()]
        rhs = self.rhs if friction else self.flawed_model()
        z = np.hstack([x, rhs(x)[:, 2:]])
        return np.column_stack([f(z) for f in self._pivot])

    def rhs(self, x, u=None) -> np.ndarray:
        """True dynamics ``dx/dt`` ``(m, 4)`` for ``x`` ``(m, 4)``; ``u`` is ignored (no input)."""
        x = self._state(x)
        a, c, d, r1, r2 = self._compiled()[2](x)
        det = a * d - c * c
        return np.column_stack([x[:, 2], x[:, 3], (d * r1 - c * r2) / det, (a * r2 - c * r1) / det])

    def flawed_model(self):
        """The frictionless pendulum (conservative prior), ``f_m(x, u)``."""
        prior = DoublePendulum(DoublePendulumParameters(**{**self.parameters.as_dict(),
                                                           "k1": 0.0, "k2": 0.0}))
        return lambda x, u=None: prior.rhs(x)

    def simulate(self, x0, t, *, rtol: float = 1e-10, atol: float = 1e-10) -> np.ndarray:
        """Integrate from ``x0`` ``(4,)`` and return the states at times ``t`` ``(m,)``, ``(m, 4)``.

        Uses :func:`discrepancy.models.simulate.simulation.integrate` with scipy's DOP853 and tight
        tolerances (the energy tests rely on them).
        """
        from ..models.simulate.simulation import integrate

        return integrate(lambda x, u: self.rhs(x), x0, t, n_states=4, n_inputs=0,
                         method="DOP853", rtol=rtol, atol=atol)

    @property
    def position_names(self) -> tuple[str, ...]:
        """Names of the two angles (the first half of the state)."""
        return STATE_NAMES[:2]

    def joints(self) -> dict:
        """``{label: relative speed}`` of the two joints (sympy), for
        :func:`~discrepancy.energy.default_friction_library`: the angles are absolute, so
        the elbow turns at ``dphi1 - dphi2``."""
        d1, d2 = symbol("dphi1"), symbol("dphi2")
        return {"joint 1": d1, "joint 2": d1 - d2}
