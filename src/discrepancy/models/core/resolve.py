"""The model's parameters resolved into the frozen set-up a fit runs on
(:class:`~discrepancy.fitting.setup.FitSetup`): the one place that reads the model's
parameters for :mod:`discrepancy.fitting`, which knows no model."""
from __future__ import annotations

import copy

from ...differentiation import get_differentiation_method
from ...differentiation.resolution import warn_if_coarse
from ...errors import ParameterError
from ...fitting.discrete import NextSample
from ...fitting.prior import Prior
from ...fitting.setup import FOLD_PROBE_ROWS, FitSetup, resolve_names
from ...libraries import PolynomialLibrary
from ...libraries.spec import parse_library
from ...optimizers import PriorOnly, get_optimizer
from .names import check_default_names, referenced_names


def resolve_setup(model, n_states: int, n_inputs: int, sample=None,
                  feature_names=None) -> FitSetup:
    """The set-up of ``model``'s parameters for ``n_states`` states and ``n_inputs`` inputs:
    names checked, defaults filled in, library specs parsed and bound, copies of the
    optimizer and differentiation method (the model's own parameters are never changed).

    ``sample``: trajectories a data-driven differentiation method (the default ``"auto"``)
    is chosen from; those with measured ``x_dot`` need none. ``feature_names``: the names of
    the states then the inputs, replacing the model's (PySINDy's ``fit(feature_names=)``)."""
    given_states, given_inputs = model.state_names, model.input_names
    if feature_names is not None:
        names = resolve_names("feature_names", feature_names, n_states + n_inputs, "", one=None)
        given_states, given_inputs = names[:n_states], names[n_states:]
    states = resolve_names("state_names", given_states, n_states, "x", one=None)
    inputs = resolve_names("input_names", given_inputs, n_inputs, "u", one="u")
    clash = sorted(set(states) & set(inputs))
    if clash:
        raise ParameterError(f"state_names and input_names must not share names; both have "
                             f"{clash}")
    library = model.feature_library
    if library is None:
        library = PolynomialLibrary(degree=2)
    elif isinstance(library, str):
        library = parse_library(library)
    check_default_names(referenced_names(model.constraints, library), states, inputs,
                        default_states=given_states is None,
                        default_inputs=given_inputs is None)
    library = copy.deepcopy(library).fit([*states, *inputs])
    if model.discrete_time:
        method, choice = NextSample(), None
    else:
        method = copy.deepcopy(get_differentiation_method(model.differentiation_method))
        method._validate_params()
        method, choice = _resolved(method, sample, states)
    optimizer = copy.deepcopy(get_optimizer(model.optimizer))
    optimizer._validate_params()
    if model.constraints is not None and not isinstance(optimizer, PriorOnly):
        if "constraints" not in optimizer.get_params(deep=False):
            raise ParameterError(f"constraints need an optimizer that takes them (STLSQ); "
                                 f"{type(optimizer).__name__} does not")
        optimizer.set_params(constraints=model.constraints.compile(
            states, library.get_feature_names()))
    probe = FOLD_PROBE_ROWS if sample is None else \
        min(FOLD_PROBE_ROWS, sum(tr.n_samples for tr in sample))
    return FitSetup(tuple(states), tuple(inputs), Prior(model.prior, states, inputs), library,
                    optimizer, method, choice, bool(model.discrete_time), probe)


def _resolved(method, sample, names):
    """A data-driven method resolved on the trajectories of ``sample`` that need it, and
    checked against their sampling (a warning when it is too coarse for the method)."""
    series = [] if sample is None else [(tr.t, tr.x) for tr in sample if tr.x_dot is None]
    if not series:  # no data, or measured derivatives: nothing to differentiate
        return method, None
    method, choice = method.choose(series) if getattr(method, "data_driven", False) else \
        (method, None)
    warn_if_coarse(method, *series[0], names)
    return method, choice
