"""The dissipation form: energy lost as the time integral of sparse, non-negative friction power.

``dH(t) = c + sum_j xi_j * int_0^t theta_j(dq) dt`` with ``xi_j >= 0``. Each ``theta_j`` is the
power (per unit coefficient) of one friction law, a non-negative function of the joint speeds,
so every learned model dissipates (passivity) and its coefficients are the friction laws.
The integral needs velocities only, never accelerations. ``c`` absorbs the error of the
reference energy ``E0 = H_m(x(0))``, which comes from a single noisy sample.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy.integrate import cumulative_trapezoid

from ..data.validation import check_array, check_times
from ..errors import ParameterError
from ..symbolic import compile_numpy, symbol


@dataclass(frozen=True)
class FrictionTerm:
    """One candidate friction law.

    Attributes:
        name: short label, e.g. ``"viscous joint 1"``.
        power: sympy expression of the dissipated power per unit coefficient (W / [unit]),
            non-negative, in the state symbols (usually the velocities only).
        unit: SI unit of the coefficient, e.g. ``"N m s"``.
        torque: the torque (or loss) law it stands for, for printing.
        functions: numpy callables for undefined sympy functions in ``power`` (name ->
            callable of the function's arguments, each ``(m,)``), e.g. a force computed by
            the system model.
        speed: the joint speed ``w`` the law acts at (sympy), when it is a torque: its torque
            per unit coefficient is ``power / |w|``, which :mod:`.soundness` limits.
    """

    name: str
    power: sp.Expr
    unit: str
    torque: str
    functions: Mapping[str, Callable] | None = field(default=None, compare=False)
    speed: sp.Expr | None = field(default=None, compare=False)

    def __post_init__(self):
        if not isinstance(self.power, sp.Basic):
            raise ParameterError(f"FrictionTerm {self.name!r}: power must be a sympy "
                                 f"expression; got {type(self.power).__name__}")


#: Stribeck speeds (rad/s) of the default library: under the turning-point constraint a
#: break-away ``F_s`` loses about ``F_s v_s^2 I / tau_g`` per reversal, so a slow ``v_s``
#: alone cannot carry a low-speed loss that a sound ``F_s`` could
STRIBECK_SPEEDS = (0.1, 0.3, 1.0)


def default_friction_library(velocity_names, *, joints=None,
                             stribeck_speed: float | tuple = STRIBECK_SPEEDS,
                             coulomb_smoothing: float | None = None) -> tuple[FrictionTerm, ...]:
    """Friction laws a tribologist would try, for any number of coordinates.

    Args:
        velocity_names: the velocity variables (e.g. ``["dq1", "dq2"]``).
        joints: ``{label: relative speed}``: what each joint turns at, as sympy expressions
            of the velocity symbols or velocity names (default: each coordinate is its own
            joint, ``{"joint i": dq_i}``). A double pendulum with absolute angles has
            ``{"joint 1": dphi1, "joint 2": dphi1 - dphi2}``.
        stribeck_speed: ``v_s`` (rad/s) of the Stribeck excess, or several (one term each,
            named with its speed, e.g. ``"Stribeck joint 1 (0.3 rad/s)"``).
        coulomb_smoothing: ``eps`` (rad/s): Coulomb friction as ``F tanh(w / eps)``.

    Per joint at speed ``w``: viscous ``k w`` (power ``k w^2``), Coulomb ``F sign(w)``
    (power ``F |w|``, or ``F w tanh(w/eps)`` smoothed) and a Stribeck excess
    ``F_s exp(-(w/v_s)^2) sign(w)``; per coordinate, quadratic air drag ``c dq |dq|``
    (power ``c |dq|^3``).
    """
    several = isinstance(stribeck_speed, (tuple, list))
    speeds_s = tuple(stribeck_speed) if several else (stribeck_speed,)
    if not speeds_s or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                               and np.isfinite(v) and v > 0 for v in speeds_s):
        raise ParameterError(f"stribeck_speed must be > 0 rad/s (or a list of such); got "
                             f"{stribeck_speed!r}")
    if coulomb_smoothing is not None and not (isinstance(coulomb_smoothing, (int, float))
                                              and coulomb_smoothing > 0):
        raise ParameterError("coulomb_smoothing must be > 0 rad/s or None; "
                             f"got {coulomb_smoothing!r}")
    if isinstance(velocity_names, str) or not velocity_names:
        raise ParameterError(f"velocity_names must be a non-empty list of names; got "
                             f"{velocity_names!r}")
    speeds = [symbol(n) for n in velocity_names]
    joints = joint_speeds(joints, speeds)
    terms = [FrictionTerm(f"viscous {label}", w ** 2, "N m s", f"k ({w})", speed=w)
             for label, w in joints.items()]
    for label, w in joints.items():
        if coulomb_smoothing is None:
            power, law = sp.Abs(w), f"F sign({w})"
        else:
            eps = sp.Float(coulomb_smoothing)
            power, law = w * sp.tanh(w / eps), f"F tanh(({w})/{coulomb_smoothing:g})"
        terms.append(FrictionTerm(f"Coulomb {label}", power, "N m", law, speed=w))
    for d in speeds:
        terms.append(FrictionTerm(f"air drag {d.name}", sp.Abs(d) ** 3, "N m s^2",
                                  f"c {d} |{d}|", speed=d))
    for label, w in joints.items():
        for v in speeds_s:
            name = f"Stribeck {label}" + (f" ({v:g} rad/s)" if several else "")
            terms.append(FrictionTerm(name, sp.Abs(w) * sp.exp(-(w / sp.Float(v)) ** 2), "N m",
                                      f"F_s exp(-(({w})/{v:g})^2) sign({w})", speed=w))
    return tuple(terms)


def _iterable(name: str, value):
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise ParameterError(f"{name} must be a sequence; got {value!r:.80}")
    return value


def without_stribeck(terms) -> tuple[FrictionTerm, ...]:
    """The library without its Stribeck terms (those of :func:`default_friction_library`)."""
    terms = tuple(_iterable("terms", terms))
    if not all(isinstance(term, FrictionTerm) for term in terms):
        raise ParameterError(f"terms must be a sequence of FrictionTerm; got {terms!r:.80}")
    return tuple(term for term in terms if not term.name.startswith("Stribeck "))


def joint_speeds(joints, speeds) -> dict[str, sp.Expr]:
    """``{label: relative speed}`` checked against the velocity symbols ``speeds`` (default:
    each coordinate its own joint)."""
    if joints is None:
        return {f"joint {i + 1}": d for i, d in enumerate(speeds)}
    if not isinstance(joints, Mapping) or not joints:
        raise ParameterError(f"joints must be a mapping of labels to relative speeds; got "
                             f"{joints!r:.80}")
    names = {d.name for d in speeds}
    out = {}
    for label, w in joints.items():
        expr = symbol(w) if isinstance(w, str) and w in names else w
        if not isinstance(expr, sp.Expr) or not expr.free_symbols or \
                not {s.name for s in expr.free_symbols} <= names:
            raise ParameterError(f"joints[{label!r}] must be a velocity name or a sympy "
                                 f"expression of {sorted(names)}; got {w!r:.60}")
        out[str(label)] = expr.xreplace({s: symbol(s.name) for s in expr.free_symbols})
    return out


def support_loss_terms(pivot_force: Callable, state_names, *,
                       static_vertical: float = 0.0) -> tuple[FrictionTerm, ...]:
    """Energy absorbed by a rig's mount: ``c Fx^2`` and ``c (Fy - W)^2``.

    ``pivot_force(x)`` ``(m, n)`` -> ``(m, 2)`` is the force (N) between pivot and pendulum,
    e.g. :meth:`~discrepancy.systems.DoublePendulum.pivot_force`; ``static_vertical`` is its
    value at rest (the weight ``W``), so that only the dynamic part counts. A mount whose
    motion under that force is dominated by damping moves at ``F / c_m`` and dissipates
    ``F^2 / c_m``; the coefficient ``c = 1 / c_m`` has the unit m / (N s).
    """
    if not callable(pivot_force):
        raise ParameterError(f"pivot_force must be a callable x (m, n) -> (m, 2); got "
                             f"{pivot_force!r:.80}")
    args = [symbol(n) for n in _iterable("state_names", state_names)]

    def component(j, offset):
        return lambda *cols: pivot_force(np.column_stack(cols))[:, j] - offset

    terms = []
    for label, j, offset in (("horizontal", 0, 0.0), ("vertical", 1, static_vertical)):
        name = f"F{'xy'[j]}"
        force = sp.Function(name)(*args)
        terms.append(FrictionTerm(f"support loss {label}", force ** 2, "m/(N s)",
                                  f"mount moving under the pivot's {label} force {name}",
                                  functions={name: component(j, offset)}))
    return tuple(terms)


def integrated_powers(terms, values: np.ndarray, t: np.ndarray, names) -> np.ndarray:
    """``int_0^t theta_j dt`` (trapezoid) for every term: ``(m, p)`` (J per unit coefficient).

    ``values`` ``(m, len(names))`` holds the variables the terms' powers use (the joint
    speeds, or the whole state for terms such as :func:`support_loss_terms`).
    """
    names = list(_iterable("names", names))
    values = check_array("values", values, n_cols=len(names), allow_1d=True)
    t = check_times("t", t, len(values))
    columns = [compile_numpy(term.power, list(names), term.functions)(values) for term in terms]
    return cumulative_trapezoid(np.column_stack(columns), t, axis=0, initial=0.0)
