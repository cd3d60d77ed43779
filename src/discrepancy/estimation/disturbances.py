"""Unmeasured disturbances as states: a force nobody recorded (a push, a load change, a
slope) that acts on some equations and wanders slowly.

Each disturbed equation ``i`` gets an extra state ``d_i`` with ``x_i' = f_i(x, u) + d_i`` and
``d_i' = w`` (a random walk whose intensity is a process-noise level, fitted by the
prediction-error route): the filter estimates the disturbance from the innovations, the way
offset-free control does, instead of the model's terms bending to explain it.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError, UnknownNameError
from .dynamics import Dynamics

#: name of the disturbance state of equation ``name``
PREFIX = "d_"


def disturbed_equations(disturbances, state_names) -> list[int]:
    """Indices of the equations named by ``disturbances`` (names or indices; ``None``:
    none)."""
    if disturbances is None:
        return []
    items = [disturbances] if isinstance(disturbances, (str, int)) else list(disturbances)
    out = []
    for i, item in enumerate(items):
        if isinstance(item, (int, np.integer)) and not isinstance(item, bool) and \
                0 <= item < len(state_names):
            out.append(int(item))
        elif isinstance(item, str) and item in state_names:
            out.append(state_names.index(item))
        else:
            raise UnknownNameError(f"disturbances[{i}] = {item!r} is not a state (name or "
                                   f"index) of {list(state_names)}")
    if len(set(out)) != len(out):
        raise ParameterError(f"disturbances names an equation twice: {items}")
    return out


def disturbance_names(state_names, equations) -> list[str]:
    """Names of the disturbance states of the equations ``equations`` (indices into
    ``state_names``): ``"d_" + state name``; :class:`~discrepancy.errors.ParameterError`
    when one would clash with a state's name."""
    names = [PREFIX + state_names[i] for i in equations]
    clash = sorted(set(names) & set(state_names))
    if clash:
        raise ParameterError(f"the disturbance states {clash} would have the names of states; "
                             "rename those states")
    return names


def with_disturbances(dyn: Dynamics, disturbances) -> Dynamics:
    """``dyn`` with a random-walk disturbance state added to each named equation."""
    equations = disturbed_equations(disturbances, list(dyn.state_names))
    if not equations:
        return dyn
    if dyn.discrete_time:
        raise ParameterError("disturbances are for continuous-time models; add the "
                             "disturbance states to a discrete-time map yourself")
    n = dyn.n
    names = disturbance_names(dyn.state_names, equations)
    rhs = dyn.rhs

    def augmented(x, u):
        out = np.zeros_like(x)
        out[:, :n] = rhs(x[:, :n], u)
        out[:, equations] += x[:, n:]
        return out

    casadi = None if dyn.casadi is None else augment_casadi(dyn.casadi, n, equations)
    return Dynamics((*dyn.state_names, *names), dyn.input_names, False, augmented, casadi,
                    dyn.parameters, dyn.why_numpy)


def augment_casadi(f, n: int, equations: list[int]):
    """``f(x, u, p)`` of ``n`` states as ``f(x_aug, u, p)`` with the disturbance states."""
    import casadi as ca

    d = len(equations)
    x, u, p = ca.SX.sym("x", n + d), ca.SX.sym("u", f.size1_in(1)), ca.SX.sym("p", f.size1_in(2))
    value = f(x[:n], u, p)
    for j, i in enumerate(equations):
        value[i] += x[n + j]
    return ca.Function("f", [x, u, p], [ca.vertcat(value, ca.SX.zeros(d))], ["x", "u", "p"],
                       ["f"])
