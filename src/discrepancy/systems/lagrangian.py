"""Any mechanical system from its Lagrangian: energy, equations of motion and friction joints.

The user writes the kinetic and potential energy (and, for the true system, a Rayleigh
dissipation function or generalised forces) as sympy expressions of named coordinates and
their rates; the equations of motion are derived with
:func:`~discrepancy.systems.mechanics.lagrange_equations` and solved numerically per sample
(``M(q) q̈ = b(q, q̇, u)``), so any number of coordinates works without an explicit inverse.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp

from ..errors import ParameterError, ShapeError
from ..expression_tape import compile_numpy_many
from ..symbolic import compile_numpy, symbol
from .base import System
from .mass_checks import check_kinetic, solve_mass, stack_columns, stack_mass
from .mechanics import lagrange_equations


def _names(value, argument: str) -> tuple[str, ...]:
    if isinstance(value, (str, sp.Symbol)) or not isinstance(value, Sequence) or not value:
        raise ParameterError(f"{argument} must be a non-empty list of names or sympy symbols; "
                             f"got {value!r:.80}")
    names = tuple(str(v.name if isinstance(v, sp.Symbol) else v) for v in value)
    if len(set(names)) != len(names) or not all(n.isidentifier() for n in names):
        raise ParameterError(f"{argument} must be distinct identifiers; got {list(names)}")
    return names


def _expression(value, argument: str, allowed: Sequence[str]) -> sp.Expr:
    if isinstance(value, (int, float)) and np.isfinite(value):
        value = sp.Float(value)
    if not isinstance(value, sp.Expr):
        raise ParameterError(f"{argument} must be a sympy expression; got "
                             f"{type(value).__name__}")
    unknown = {s.name for s in value.free_symbols} - set(allowed)
    if unknown:
        raise ParameterError(f"{argument} uses {sorted(unknown)}, which are neither "
                             f"coordinates, rates nor inputs ({list(allowed)}); substitute "
                             "numbers for the parameters first")
    return value.xreplace({s: symbol(s.name) for s in value.free_symbols})


class LagrangianSystem(System):
    """A mechanical system given by ``L = T - V`` in sympy.

    Args:
        kinetic, potential: ``T`` and ``V`` (J), sympy expressions of the coordinates and
            rates (numbers substituted for every parameter); ``T`` must be positive for
            every motion (its mass matrix ``∂²T/∂q̇²`` positive definite: checked at random
            states, :mod:`~discrepancy.systems.mass_checks`).
        coordinates: names (or symbols) of the generalised coordinates ``q``, e.g.
            ``["phi"]``.
        rates: names of their time derivatives (default ``"d" + name``).
        dissipation: Rayleigh dissipation function ``D(q̇)`` (W/2) of the *true* system:
            ``∂D/∂q̇_i`` is the friction force of coordinate ``i``; the flawed model drops it.
        forces: generalised forces ``Q_i`` (N or N m) in coordinates, rates and inputs, e.g.
            a motor torque ``[u]``; kept by the flawed model.
        input_names: names of the inputs used in ``forces``.
        joints: ``{label: relative speed}`` for friction laws (default: each coordinate is
            its own joint). A chain in absolute angles has ``{"joint 2": dphi2 - dphi1}``.

    States are ``x = [q, q̇]``; ``energy`` is the conservative ``H_m = T + V``.
    """

    def __init__(self, kinetic, potential, coordinates, *, rates=None, dissipation=0,
                 forces=None, input_names=(), joints=None):
        q = _names(coordinates, "coordinates")
        dq = _names(rates, "rates") if rates is not None else tuple(f"d{n}" for n in q)
        if len(dq) != len(q):
            raise ParameterError(f"rates must name one rate per coordinate ({len(q)}); got "
                                 f"{len(dq)}")
        if isinstance(input_names, str):
            raise ParameterError(f"input_names must be a list of names; got {input_names!r}")
        inputs = _names(list(input_names), "input_names") if len(input_names) else ()
        states = (*q, *dq)
        if len(set(states + inputs)) != len(states) + len(inputs):
            raise ParameterError(f"input_names {list(inputs)} repeat a coordinate or rate name")
        self.state_names, self.input_names = states, inputs
        self.kinetic = _expression(kinetic, "kinetic", states)
        check_kinetic(self.kinetic, q, dq)
        self.potential = _expression(potential, "potential", q)
        self.dissipation = _expression(dissipation, "dissipation", states)
        if forces is not None and (isinstance(forces, (str, sp.Basic))
                                   or not isinstance(forces, Sequence) or len(forces) != len(q)):
            raise ParameterError(f"forces must be a list of {len(q)} expressions (one per "
                                 f"coordinate); got {forces!r:.80}")
        self.forces = [_expression(f, f"forces[{i}]", states + inputs)
                       for i, f in enumerate(forces or [0] * len(q))]
        self._joints = joints
        self._compiled = {}

    @property
    def position_names(self) -> tuple[str, ...]:
        """Names of the coordinates (the first half of the state; their velocities follow)."""
        return self.state_names[:len(self.state_names) // 2]

    def joints(self) -> dict:
        """``{label: relative speed}`` for :func:`~discrepancy.energy.default_friction_library`."""
        from ..energy.dissipation import joint_speeds

        k = len(self.position_names)
        return joint_speeds(self._joints, [symbol(n) for n in self.state_names[k:]])

    def _functions(self, friction: bool):
        if friction not in self._compiled:
            k = len(self.position_names)
            syms = [symbol(n) for n in self.state_names]
            _, mass, rest = lagrange_equations(
                self.kinetic, self.potential, syms[:k], syms[k:],
                dissipation=self.dissipation if friction else sp.S.Zero, forces=self.forces,
                simplify=False)
            names = (*self.state_names, *self.input_names)
            # one tape: the entries of M and b share their sines and cosines
            self._compiled[friction] = compile_numpy_many(
                [e for row in mass.tolist() for e in row] + list(rest), names)
        return self._compiled[friction]

    def _states(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        x = x[None, :] if x.ndim == 1 else x
        if x.ndim != 2 or x.shape[1] != len(self.state_names):
            raise ShapeError(f"x must be (m, {len(self.state_names)}) = "
                             f"{list(self.state_names)}; got shape {x.shape}")
        return x

    def _dynamics(self, x, u, friction: bool) -> np.ndarray:
        """``[q̇, q̈]`` with ``M(q) q̈ = b(q, q̇, u)`` solved per sample."""
        x = self._states(x)
        z, m, r = x, len(x), len(self.input_names)
        if r:
            if u is None:
                raise ShapeError(f"u is required: (m, {r}) = {list(self.input_names)}")
            z = np.hstack([x, np.broadcast_to(np.asarray(u, float).reshape(-1, r), (m, r))])
        k = len(self.position_names)
        values = self._functions(friction)(z)
        matrix = stack_mass(values, k, m)
        b = stack_columns(values[k * k:], m)
        acc = solve_mass(matrix, b, x, self.state_names)
        return np.hstack([x[:, len(self.position_names):], acc])

    def rhs(self, x, u=None) -> np.ndarray:
        """True dynamics ``[q̇, q̈]`` ``(m, 2k)`` (with the dissipation function)."""
        return self._dynamics(x, u, True)

    def flawed_model(self):
        """The conservative model (no dissipation function), ``f_m(x, u)``."""
        return lambda x, u=None: self._dynamics(x, u, False)

    def _evaluate(self, key: str, exprs, x) -> np.ndarray:
        """The expressions ``exprs`` of the state, compiled once under ``key``, ``(m, len)``."""
        if key not in self._compiled:
            self._compiled[key] = [compile_numpy(e, self.state_names) for e in exprs]
        x = self._states(x)
        return np.column_stack([np.broadcast_to(f(x), (len(x),))
                                for f in self._compiled[key]])

    def energy(self, x) -> np.ndarray:
        """``H_m = T + V`` (J), ``(m,)``."""
        return self._evaluate("energy", [self.kinetic + self.potential], x)[:, 0]

    def conservative_torques(self, x) -> np.ndarray:
        """``-∂V/∂q`` (N m or N) per coordinate, ``(m, k)``: the gravity and spring torques."""
        return self._evaluate("torques", [-sp.diff(self.potential, symbol(n))
                                          for n in self.position_names], x)

    def simulate(self, x0, t, *, u=None, rtol: float = 1e-10, atol: float = 1e-10) -> np.ndarray:
        """Integrate the true system from ``x0`` ``(2k,)``; states at times ``t``, ``(m, 2k)``.
        ``u``: inputs ``(m, r)`` at ``t`` (held linearly) or a callable ``u(t)``."""
        from ..models.simulate.simulation import integrate

        return integrate(self.rhs, x0, t, u=u, n_states=len(self.state_names),
                         n_inputs=len(self.input_names), method="DOP853", rtol=rtol, atol=atol)

