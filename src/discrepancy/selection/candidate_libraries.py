"""Candidate libraries built from the data and the prior, for :func:`choose_procedure`.

The defaults cover what mechanical, fluid and electrical priors usually miss, each as an
exact sympy library (so a chosen model exports like any other):

* polynomials of degree 1, 2 and 3 in the states and inputs;
* friction laws of each velocity-like state: viscous ``v``, smoothed Coulomb
  ``tanh(v / ε)`` and a Stribeck bump ``exp(-(v / v_s)²) tanh(v / ε)``, with ``ε`` a
  fiftieth and ``v_s`` the median of ``|v|`` over the data (a tenth smoothed a true Coulomb
  law so much that hinges forecast it better). A state is velocity-like when the prior's
  equation of another state is that state (``(q)' = v``), which the prior's expressions or
  its values on the data show;
* hinges ``max(0, z - k)`` with knots ``k`` at the 25, 50 and 75 % quantiles of every
  state and input (overflows, dead zones, piecewise-linear springs), and saturations
  ``tanh((z - median) / spread)``;
* square roots ``sign(z) sqrt(|z|)`` of every state and input that keeps one sign over
  the data, or has none (Torricelli outflow of a level, quadratic drag inverted): the root
  of a variable that crosses zero has an infinite slope there, which no physical law of
  the kind needs and which makes output-error fits crawl;
* ``sin`` and ``cos`` of every angle, with the linear terms of the other variables: a
  state is an angle when the prior sees it only through 2π-periodic functions (its values
  on the data do not change when the state moves by 2π, and do when it moves by 1). A
  pendulum's wrong length or a tilted mount is a multiple of ``sin q`` and ``cos q``; a
  power of an angle that goes over the top extrapolates without bound.

For output-error fits, states no output measures take their values along the prior's
simulation (:func:`~discrepancy.models.outputs.output_checks.prior_states`), so their knots,
scales and signs come from the data too.

Each nonlinear family comes with the linear terms (``linear + friction`` etc.), so a
candidate never lacks the simplest correction, and one candidate joins the degree-2
polynomials with roots and hinges (fluid systems: flows of levels and overflows).
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..errors import ShapeError
from ..fitting.prior import Prior
from ..libraries import CustomLibrary, PolynomialLibrary
from ..symbolic import symbol

#: quantiles of each variable where hinges are placed
KNOT_QUANTILES = (0.25, 0.5, 0.75)


def _number(value: float) -> sp.Float:
    return sp.Float(float(f"{value:.3g}"))


def velocity_states(prior, state_names, x, u=None) -> list[str]:
    """States that are the derivative of another state in the prior: ``(q)' = v`` (exactly,
    for a sympy prior; to 1e-9 on the data ``x`` ``(m, n)`` for a callable)."""
    if prior is None:
        return []
    if isinstance(prior, (list, tuple)):
        names = {sp.Symbol(n, real=True): n for n in state_names}
        out = []
        for expr in prior:
            e = sp.sympify(expr)
            e = e.xreplace({s: sp.Symbol(s.name, real=True) for s in e.free_symbols})
            if e in names and names[e] not in out:
                out.append(names[e])
        return out
    rows = x[:min(len(x), 200)]
    try:
        values = np.asarray(prior(rows, None if u is None else u[:len(rows)]), dtype=float)
    except Exception:          # a prior that cannot be evaluated here has no kinematics
        return []
    out = []
    for i in range(values.shape[1]):
        for j, name in enumerate(state_names):
            if j != i and name not in out and np.allclose(values[:, i], rows[:, j],
                                                          rtol=1e-9, atol=1e-12):
                out.append(name)
    return out


def angle_states(prior, state_names, input_names, x, u=None) -> list[str]:
    """States the prior sees only through 2π-periodic functions (module doc), judged on the
    first 200 rows of the data ``x`` ``(m, n)`` and ``u`` ``(m, r)``: the prior's values
    equal to 1e-9 with the state moved by 2π and differ with it moved by 1."""
    if prior is None:
        return []
    rows = np.asarray(x, float)[:min(len(x), 200)]
    inputs = None if u is None else np.asarray(u, float)[:len(rows)]
    try:
        model = Prior(prior, state_names, input_names)
        with np.errstate(all="ignore"):
            base = model.unchecked(rows, inputs)
            moved = [[model.unchecked(_moved(rows, j, shift), inputs)
                      for shift in (2 * np.pi, 1.0)] for j in range(len(state_names))]
    except Exception:          # a prior that cannot be evaluated here names no angle
        return []
    finite = np.isfinite(base)
    return [name for name, (turn, step) in zip(state_names, moved, strict=True)
            if np.allclose(turn[finite], base[finite], rtol=1e-9, atol=1e-12)
            and not np.allclose(step[finite], base[finite], rtol=1e-9, atol=1e-12)]


def _moved(rows, j, shift):
    out = rows.copy()
    out[:, j] += shift
    return out


def trigonometric_library(angles, others) -> CustomLibrary | PolynomialLibrary:
    """``sin`` and ``cos`` of each angle with the linear terms (and a constant) of the
    ``others`` variables."""
    trig = CustomLibrary([f(symbol(a)) for a in angles for f in (sp.sin, sp.cos)])
    return PolynomialLibrary(1, variables=list(others)) + trig if others else \
        CustomLibrary([sp.Integer(1)]) + trig


def friction_library(velocities: dict[str, np.ndarray]) -> CustomLibrary | None:
    """Smoothed Coulomb and Stribeck terms of each velocity (viscous is in the linear
    terms); ``velocities``: name -> its samples."""
    terms = []
    for name, v in velocities.items():
        speed = np.abs(v[np.isfinite(v)])
        scale = float(np.median(speed)) if speed.size else 0.0
        if scale <= 0:
            continue
        s, sharp = symbol(name), _number(50 / scale)       # 1 / ε and 1 / v_s², rounded
        coulomb = sp.tanh(sharp * s)
        terms += [coulomb, sp.exp(-_number(scale ** -2) * s ** 2) * coulomb]
    return CustomLibrary(terms) if terms else None


def hinge_library(data: dict[str, np.ndarray]) -> CustomLibrary | None:
    """Hinges ``max(0, z - k)`` at the quantile knots and one saturation per variable."""
    terms = []
    for name, z in data.items():
        s = symbol(name)
        knots = np.unique([_number(k) for k in np.quantile(z, KNOT_QUANTILES)])
        terms += [sp.Max(0, s - k) for k in knots]
        spread = float(np.quantile(z, 0.9) - np.quantile(z, 0.1))
        if spread > 0:
            terms.append(sp.tanh(_number(2 / spread) * (s - _number(np.median(z)))))
    return CustomLibrary(terms) if terms else None


def root_library(names) -> CustomLibrary:
    """``sign(z) sqrt(|z|)`` of each variable."""
    return CustomLibrary([sp.sign(symbol(n)) * sp.sqrt(sp.Abs(symbol(n))) for n in names])


def default_libraries(state_names, input_names, x: np.ndarray, u: np.ndarray | None = None,
                      *, prior=None, measured=None) -> dict:
    """The default candidate libraries (module doc) for data ``x`` ``(m, n)`` and ``u``
    ``(m, r)``, in order of growing size. ``measured``: the variables with data (default
    all; a column with NaN has none); knots, scales and signs come from them, other
    states get polynomial and root terms only."""
    names = [*state_names, *input_names]
    columns = x if u is None else np.hstack([x, u])
    if np.ndim(columns) != 2 or np.shape(columns)[1] != len(names):
        raise ShapeError(f"state_names and input_names name {len(names)} variables; x and u "
                         f"hold {np.shape(columns)[1:]} columns")
    measured = names if measured is None else list(measured)
    data = {n: columns[:, names.index(n)] for n in measured if n in names
            and np.all(np.isfinite(columns[:, names.index(n)]))}
    linear = PolynomialLibrary(1)
    out = {"linear": linear, "polynomial 2": PolynomialLibrary(2),
           "polynomial 3": PolynomialLibrary(3)}
    speeds = [v for v in velocity_states(prior, state_names, x, u) if v in data]
    friction = friction_library({v: data[v] for v in speeds})
    if friction is not None:
        out["linear + friction"] = PolynomialLibrary(1) + friction
    hinges = hinge_library(data)
    if hinges is not None:
        out["linear + hinges"] = PolynomialLibrary(1) + hinges
    signed = [n for n in names if n not in data or np.all(data[n] >= 0)
              or np.all(data[n] <= 0)]
    if signed:
        out["linear + roots"] = PolynomialLibrary(1) + root_library(signed)
    if hinges is not None:
        quadratic = PolynomialLibrary(2) + root_library(signed) if signed else \
            PolynomialLibrary(2)
        out["polynomial 2 + roots + hinges"] = quadratic + hinge_library(data)
    angles = angle_states(prior, state_names, input_names, x, u)
    if angles:
        out["linear + trigonometric"] = trigonometric_library(
            angles, [n for n in names if n not in angles])
    return out
