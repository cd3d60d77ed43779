"""The model a filter runs: a fitted hybrid model, a numpy prior or sympy expressions.

:func:`dynamics_of` turns any of them into :class:`Dynamics`: names, the vectorised numpy
right-hand side and, when CasADi is installed and the model can be written in it, its
CasADi form ``f(x, u, p)`` (exact, so filters get exact Jacobians; ``p`` holds parameters
that a prediction-error fit varies, none for a given model). A model CasADi cannot express
(a callable prior that branches on values, a numpy-only library term) runs on the numpy
form, with Jacobians by central differences (see :mod:`discrepancy.estimation.backends`).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from .._optional import require
from ..data.validation import check_vector
from ..errors import (
    ExportError,
    MissingDependencyError,
    ParameterError,
    ShapeError,
    describe,
)
from ..fitting.prior import Prior
from ..fitting.setup import resolve_names
from ..hybrid.casadi_form import casadi_module, hybrid_function, prior_expression

BACKENDS = ("auto", "casadi", "numpy")


@dataclass
class Dynamics:
    """``x' = f(x, u)`` (or the map ``x[k+1] = f(x[k], u[k])`` when ``discrete_time``).

    Attributes:
        state_names, input_names: the ``n`` states and ``r`` inputs.
        rhs: numpy ``rhs(x (m, n), u (m, r) or None) -> (m, n)``.
        casadi: CasADi Function ``f(x (n,), u (r,), p (q,)) -> (n,)`` or ``None``.
        parameters: ``p`` ``(q,)`` to evaluate ``casadi`` with (empty for a given model).
        why_numpy: why ``casadi`` is ``None`` (for messages), else ``None``.
    """

    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    discrete_time: bool
    rhs: Any
    casadi: Any = None
    parameters: np.ndarray | None = None
    why_numpy: str | None = None

    @property
    def n(self) -> int:
        """Number of states ``n``."""
        return len(self.state_names)

    @property
    def r(self) -> int:
        """Number of inputs ``r`` (0 without inputs)."""
        return len(self.input_names)


def dynamics_of(model, *, state_names=None, input_names=None, discrete_time=None,
                n_states: int | None = None, backend: str = "auto") -> Dynamics:
    """:class:`Dynamics` of a fitted ``DiscrepancyModel``, a callable prior
    ``f(x (m, n), u (m, r)) -> (m, n)`` or a list of ``n`` sympy expressions.

    ``state_names`` and ``input_names`` name the variables of a callable or expressions
    (default ``x1 ...`` for ``n_states`` states, no inputs); a fitted model brings its own.
    ``backend``: ``"casadi"`` (required: an error when it cannot be used), ``"numpy"`` or
    ``"auto"`` (CasADi when installed and the model can be written in it)."""
    if isinstance(model, Dynamics):           # built by the library (prediction-error fits)
        return model
    if backend not in BACKENDS:
        raise ParameterError(f"backend must be one of {', '.join(map(repr, BACKENDS))}; got "
                             f"{backend!r}")
    if hasattr(model, "fit_prediction_error"):     # a DiscrepancyModel (not imported: a cycle)
        model.check_is_fitted()
        if state_names is not None or input_names is not None:
            raise ParameterError("state_names and input_names come from the fitted model; "
                                 "do not give them with a DiscrepancyModel")
        if discrete_time is not None and bool(discrete_time) != model.discrete_time:
            raise ParameterError(f"discrete_time={discrete_time} contradicts the model "
                                 f"(discrete_time={model.discrete_time})")
        dyn = Dynamics(tuple(model.state_names_), tuple(model.input_names_),
                       model.discrete_time, model._rhs_one)
        return _with_casadi(dyn, backend, lambda: _model_function(model))
    prior = _prior_of(model, state_names, input_names, n_states)
    dyn = Dynamics(tuple(prior.names[:prior.n]), tuple(prior.names[prior.n:]),
                   bool(discrete_time), prior)
    return _with_casadi(dyn, backend, lambda: _prior_function(prior))


def _prior_of(model, state_names, input_names, n_states) -> Prior:
    if isinstance(model, sp.MatrixBase):
        model = list(model)
    if isinstance(model, (list, tuple)):
        if not model:
            raise ParameterError("model must not be an empty list of expressions")
        n = len(model)
    elif callable(model):
        if state_names is None and n_states is None:
            raise ParameterError("a callable model needs state_names= (or process noise of "
                                 "one value per state) to know its number of states")
        n = len(state_names) if isinstance(state_names, (list, tuple)) else \
            (1 if isinstance(state_names, str) else int(n_states))
    else:
        raise ParameterError("model must be a fitted DiscrepancyModel, a callable "
                             f"f(x, u) -> (m, n) or a list of sympy expressions; got "
                             f"{describe(model)}")
    states = resolve_names("state_names", state_names, n, "x", one=None)
    inputs = [] if input_names is None else \
        resolve_names("input_names", input_names, 1 if isinstance(input_names, str)
                      else len(input_names), "u", one="u")
    clash = sorted(set(states) & set(inputs))
    if clash:
        raise ParameterError(f"state_names and input_names must not share names; both have "
                             f"{clash}")
    return Prior(model, states, inputs)


def _with_casadi(dyn: Dynamics, backend: str, build) -> Dynamics:
    if backend == "numpy":
        dyn.why_numpy = "backend='numpy' was asked for"
        return dyn
    try:
        require("casadi", purpose="compiled filters with exact Jacobians")
    except MissingDependencyError as e:
        if backend == "casadi":
            raise
        dyn.why_numpy = str(e)
        return dyn
    try:
        dyn.casadi = build()
    except ExportError as e:
        if backend == "casadi":
            raise
        dyn.why_numpy = f"the model cannot be written in CasADi ({e})"
        warnings.warn(f"{dyn.why_numpy}; the filter steps in numpy with Jacobians by central "
                      "differences (slower and less exact): give the prior as sympy "
                      "expressions to use CasADi", stacklevel=4)
        return dyn
    dyn.parameters = np.zeros(0)
    return dyn


def check_points(n: int, r: int):
    """Points a traced callable is compared with numpy on: positive values of moderate size
    (a prior may take logarithms or square roots of its states)."""
    rng = np.random.default_rng(0)
    return rng.uniform(0.1, 1.0, (4, n)), (rng.uniform(0.1, 1.0, (4, r)) if r else None)


def _model_function(model):
    ca = casadi_module()
    f = hybrid_function(model, check_points=check_points(model.n_states_, model.n_inputs_))
    return _parametrised(ca, f, model.n_states_, model.n_inputs_)


def _prior_function(prior: Prior):
    ca = casadi_module()
    n, r = prior.n, len(prior.names) - prior.n
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", r)
    column = prior_expression(prior, x, u, check_points=check_points(n, r))
    return _parametrised(ca, ca.Function("prior", [x, u], [column]), n, r)


def _parametrised(ca, f, n: int, r: int):
    """``f(x, u)`` as ``f(x, u, p)`` with an empty ``p`` (the filters' common signature)."""
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("p", 0)
    return ca.Function("f", [x, u, p], [f(x, u) if r else f(x, u)], ["x", "u", "p"], ["f"])


def check_state(name: str, value, n: int) -> np.ndarray:
    """A state ``(n,)`` of finite numbers."""

    arr = np.asarray(value, dtype=float) if isinstance(value, np.ndarray) else value
    try:
        return check_vector(name, arr, n)
    except ShapeError:
        raise ShapeError(f"{name} must be {n} finite numbers (one per state); got "
                         f"{describe(value)}") from None
