"""``PDEDiscrepancyModel.simulate``: checks, the right-hand side, the integrator's choice."""
from __future__ import annotations

import numpy as np

from ..constraints import Interval as _Interval
from ..constraints import Options, Real, validate_params
from ..data.fields import field_array
from ..data.validation import check_times
from ..errors import ParameterError, ShapeError, describe
from .simulation import (
    SpectralJet,
    boundary_mask,
    check_method,
    fourier_symbols,
    jacobian_sparsity,
    linear_part,
    run_etdrk4,
    run_solve_ivp,
    simulation_methods,
)


def simulate(model, u0, t, *, inputs, method, rtol, atol, boundary):
    """See :meth:`~discrepancy.pde.model.PDEDiscrepancyModel.simulate`."""
    grid, n = model.grid_, len(model.field_names_)
    validate_params("simulate", {"rtol": rtol, "atol": atol, "boundary": boundary},
                    {"rtol": [_Interval(Real, 0, 1, closed="neither")],
                     "atol": [_Interval(Real, 0, None, closed="neither")],
                     "boundary": [Options(["fixed", "free"])]})
    u0 = field_array("u0", np.asarray(u0, dtype=float)[None], grid, n_fields=n)[0]
    if np.ndim(t) != 1 or len(t) < 2:
        raise ShapeError(f"t must be the output times, a 1-D array of at least 2; got "
                         f"{describe(t)}")
    t = check_times("t", t, len(t))
    input_at = _input_function(inputs, grid, len(model.input_names_))
    methods = simulation_methods(grid)

    def rhs(u, time):
        return model._evaluate(u[None], input_at(time), methods, "hybrid", check=False)[0]

    model._evaluate(u0[None], input_at(t[0]), methods, "hybrid")  # checked once, by name

    symbolic = model.prior is None or model.prior_.is_symbolic
    method = check_method(method, symbolic, grid)
    if method == "etdrk4":
        return _etdrk4(model, u0, t, input_at, rtol)
    fixed = None
    if boundary == "fixed" and not all(grid.periodic):
        fixed = boundary_mask(grid, n)
    sparsity = None
    if symbolic and method in ("BDF", "Radau"):
        sparsity = jacobian_sparsity(grid, n, model.setup_.variables.order)
    return run_solve_ivp(rhs, u0, t, method=method, rtol=rtol, atol=atol, fixed=fixed,
                         sparsity=sparsity)


def _etdrk4(model, u0, t, input_at, rtol):
    """ETDRK4 with the hybrid's exact expressions evaluated on a spectral jet."""
    from ..symbolic import compile_numpy

    grid = model.grid_
    exprs = model.to_sympy("hybrid")
    terms = linear_part(exprs, model.field_names_, grid.names)
    L = np.stack([fourier_symbols(grid, tj) for tj in terms], axis=-1)
    variables = model.setup_.variables
    jet = SpectralJet(grid, variables, {s.name for e in exprs for s in e.free_symbols})
    names = variables.names
    compiled = [compile_numpy(e, names, model.feature_library_.user_functions())
                for e in exprs]
    axes = tuple(range(grid.ndim))

    def N(v, time):
        z = jet(v)
        f = input_at(time)
        if f is not None:
            z = np.concatenate([z, f[0]], axis=-1)
        flat = z.reshape(-1, z.shape[-1])
        rhs = np.stack([np.broadcast_to(c(flat), flat.shape[:1]) for c in compiled], axis=-1)
        return np.fft.rfftn(rhs.reshape(*grid.shape, -1), axes=axes) - L * v

    return run_etdrk4(N, L, u0, t, grid, rtol=rtol)


def _input_function(inputs, grid, r: int):
    """``time -> (1, *grid.shape, r)`` (or ``None`` without inputs) from a callable."""
    if r == 0:
        if inputs is not None:
            raise ShapeError("inputs were given but the model was fitted without inputs")
        return lambda time: None
    if not callable(inputs):
        raise ParameterError(f"the model has {r} inputs: give inputs as a callable f(t) "
                             f"returning ({', '.join(map(str, grid.shape))}, {r}) or ({r},); "
                             f"got {describe(inputs)}")

    def at(time):
        value = np.asarray(inputs(time), dtype=float)
        if value.shape == (r,):
            value = np.broadcast_to(value, (*grid.shape, r))
        if value.shape != (*grid.shape, r) or not np.all(np.isfinite(value)):
            raise ShapeError(f"inputs(t) must return finite values of shape "
                             f"{(*grid.shape, r)} or ({r},); got {describe(value)} at t = {time}")
        return value[None]
    return at
