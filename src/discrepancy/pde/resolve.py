"""Resolving a PDE model's parameters into a :class:`~discrepancy.pde.setup.FieldSetup`.

Names are checked, the default library is sized from the prior (its derivative order, at
least 2), the jet holds every derivative the library or the prior names, and the time and
space differentiation are chosen from the data when they are ``"auto"``
(:mod:`discrepancy.pde.auto`). The model's own parameters are never changed.
"""
from __future__ import annotations

import copy

from ..differentiation import Differentiator, get_differentiation_method
from ..differentiation.spatial import SpatialDifferentiator, get_spatial_method
from ..errors import ParameterError
from ..libraries import FeatureLibrary, PolynomialLibrary
from ..libraries.pde import PDELibrary, library_derivative_order
from ..models.setup import resolve_names
from ..optimizers import get_optimizer
from .prior import FieldPrior
from .setup import FieldSetup
from .variables import FieldVariables
from .weak import FieldWeakForm

#: the default library: PDE-FIND's products of cubic polynomials of the fields (with a
#: constant) and their derivatives, to the highest order (at most 4) that keeps it within
#: DEFAULT_COLUMNS columns, and never below the prior's order or 2
DEFAULT_DEGREE = 3
#: highest derivative order of the default library
DEFAULT_MAX_ORDER = 4
#: most columns of the default library (its derivative order is lowered to stay within)
DEFAULT_COLUMNS = 120


def default_library(prior_order: int, n_fields: int, ndim: int) -> PDELibrary:
    """The default library (see :data:`DEFAULT_COLUMNS`): one field in 1-D gets fourth
    derivatives (20 columns), two fields in 2-D second ones (110 columns)."""
    from math import comb

    from ..libraries.pde import multiindices

    functions = comb(n_fields + DEFAULT_DEGREE, DEFAULT_DEGREE)
    order = max(2, prior_order)
    for k in range(DEFAULT_MAX_ORDER, order, -1):
        if functions * (1 + n_fields * len(multiindices(ndim, k))) <= DEFAULT_COLUMNS:
            order = k
            break
    return PDELibrary(PolynomialLibrary(DEFAULT_DEGREE, include_bias=True),
                      derivative_order=order)


def resolve_setup(model, n_fields: int, n_inputs: int, grid, sample=None,
                  lengths=None) -> FieldSetup:
    """The set-up of ``model`` for ``n_fields`` fields and ``n_inputs`` inputs on ``grid``;
    ``sample``: the first snapshots of the data, which data-driven choices look at
    (:func:`first_snapshots`); ``lengths``: the snapshots of every run (default: those of
    the sample)."""
    fields = resolve_names("field_names", model.field_names, n_fields, "u", one="u")
    inputs = resolve_names("input_names", model.input_names, n_inputs, "f", one="f")
    taken = set(grid.names) | {"t"}
    clash = sorted((set(fields) | set(inputs)) & taken) or sorted(set(fields) & set(inputs))
    if clash:
        raise ParameterError(f"field and input names must differ from each other and from "
                             f"the coordinates {list(grid.names)} and 't'; {clash} clash")
    prior = FieldPrior(model.prior, fields, grid.names, inputs)
    library = model.feature_library
    if library is None:
        library = default_library(prior.order, n_fields, grid.ndim)
    elif not isinstance(library, FeatureLibrary):
        raise ParameterError(f"feature_library must be a feature library (e.g. PDELibrary()); "
                             f"got {type(library).__name__}")
    order = max(library_derivative_order(library, fields, grid.names), prior.order)
    variables = FieldVariables(tuple(fields), tuple(grid.names), tuple(inputs), order)
    library = copy.deepcopy(library).fit(variables.names)
    optimizer = copy.deepcopy(get_optimizer(model.optimizer))
    optimizer._validate_params()
    if lengths is None:
        lengths = [r.n_samples for r in sample] if sample else [1000]
    time_methods, spatial, choice = resolve_methods(model, grid, sample, n_fields, order,
                                                    min(lengths))
    return FieldSetup(variables, grid, prior, library, optimizer, time_methods, spatial,
                      choice, int(sum(lengths)))


#: snapshots (from the start of the data, over runs in order) that choices look at
SAMPLE_SNAPSHOTS = 512


def first_snapshots(runs, budget: int = SAMPLE_SNAPSHOTS) -> list:
    """The first ``budget`` snapshots of ``runs`` (whole runs first, the last one cut):
    the same rows in memory, streamed or on Dask, so the same choices."""
    out = []
    for run in runs:
        if budget <= 0:
            break
        k = min(run.n_samples, budget)
        out.append(run if k == run.n_samples else type(run)(
            run.t[:k], run.u[:k], None if run.inputs is None else run.inputs[:k], run.grid))
        budget -= k
    return out


def resolve_methods(model, grid, sample, n_fields: int, order: int, shortest: int):
    """``(time_methods, spatial, choice)`` from the model's differentiation parameters
    (``shortest``: snapshots of the shortest run)."""
    from .auto import choose

    method = model.differentiation_method
    spatial = _spatial(model.spatial_differentiation, grid)
    if method is None or method == "auto":
        if not sample:
            raise ParameterError("differentiation_method='auto' chooses from the data; give "
                                 "the data (fit) or a method")
        return choose(sample, grid, order, shortest, spatial=spatial)
    if isinstance(method, str) and method == "weak":
        method = FieldWeakForm()
    if isinstance(method, FieldWeakForm):
        method._validate_params()
        if sample and (method.data_driven or spatial is None or method.noise_std is None):
            return choose(sample, grid, order, shortest, spatial=spatial, weak=method)
        if method.data_driven:
            raise ParameterError("a weak form with widths=None chooses them from the data; "
                                 "give the data (fit) or widths")
        return (_powered(method, order),), spatial or _spatial("auto", grid, clean=True), None
    method = copy.deepcopy(get_differentiation_method(method))
    if not isinstance(method, Differentiator):
        raise ParameterError(f"differentiation_method must be 'auto', 'weak', a FieldWeakForm "
                             f"or a time Differentiator; got {method!r}")
    method._validate_params()
    if getattr(method, "data_driven", False):
        from .auto import time_smoothing

        methods, info = time_smoothing(sample, method)
        return methods, spatial or _spatial("auto", grid, clean=True), info
    return (method,) * n_fields, spatial or _spatial("auto", grid, clean=True), None


def _powered(form: FieldWeakForm, order: int) -> FieldWeakForm:
    if form.power is not None:
        return form
    return FieldWeakForm(form.widths, power=max(8, 2 * order + 2), stride=form.stride)


def _spatial(given, grid, *, clean: bool = False):
    """One spatial method per axis from the parameter (``None``/"auto": decided from the
    data, unless ``clean``: spectral on periodic axes, 6th-order differences elsewhere)."""
    from ..differentiation.spatial import SpatialFiniteDifference, SpatialSpectral

    if given is None or given == "auto":
        if not clean:
            return None
        return tuple(SpatialSpectral() if p else SpatialFiniteDifference(6)
                     for p in grid.periodic)
    items = list(given) if isinstance(given, (list, tuple)) else [given] * grid.ndim
    if len(items) != grid.ndim:
        raise ParameterError(f"spatial_differentiation must be one method or one per axis "
                             f"({grid.ndim}); got {len(items)}")
    methods = tuple(copy.deepcopy(get_spatial_method(m)) if not isinstance(
        m, SpatialDifferentiator) else copy.deepcopy(m) for m in items)
    for m, p, name in zip(methods, grid.periodic, grid.names, strict=True):
        m._validate_params()
        if m.periodic_only and not p:
            raise ParameterError(f"{type(m).__name__} needs a periodic axis; axis {name!r} is "
                                 "not periodic")
    return methods
