"""Exact export of a fitted PDE model to sympy and LaTeX.

The jet symbols (``u_xx``) print in LaTeX as subscripts (``u_{xx}``); ``derivatives=True``
gives the same equations with ``sympy.Derivative`` of functions ``u(t, x)`` instead, for
further symbolic work (substitution, linearisation, a solver of your own).
"""
from __future__ import annotations

import sympy as sp

from ..constraints import Integral, Interval, validate_params
from ..libraries.pde import parse_derivative
from ..models.files.export import discrepancy_expressions, exported_part
from ..symbolic import symbol


class ExportView:
    """The attributes the ODE export helpers read, for a fitted PDE model."""

    def __init__(self, model):
        self.model = model
        self.coef_ = model.coef_
        self.feature_expressions_ = model.feature_expressions_
        self.prior = model.prior
        self.prior_ = model.prior_
        self.state_names_ = model.field_names_
        self.variable_names_ = model.setup_.variables.names

    def get_feature_names(self):
        """The PDE model's feature names."""
        return self.model.get_feature_names()

    def check_is_fitted(self):
        """The PDE model's own check."""
        self.model.check_is_fitted()


def to_sympy(model, part=None, derivatives: bool = False) -> list[sp.Expr]:
    """One sympy expression per field for ``u_t`` of a fitted PDE model (see
    :meth:`~discrepancy.PDEDiscrepancyModel.to_sympy`): the hybrid ``N_m + g`` or, with
    ``part="discrepancy"`` (the default when the prior is a callable), ``g`` alone; in
    jet symbols (``u_xx``), or with ``derivatives=True`` in ``sympy.Derivative`` form."""
    view = ExportView(model)
    part = exported_part(view, part)
    g = discrepancy_expressions(view)
    exprs = g if part == "discrepancy" or not model.prior_.is_symbolic else [
        f + gi for f, gi in zip(model.prior_.expressions, g, strict=True)]
    return [as_derivatives(e, model) for e in exprs] if derivatives else exprs


def as_derivatives(expr: sp.Expr, model) -> sp.Expr:
    """``expr`` with jet symbols replaced by derivatives of ``u(t, x, ...)``."""
    grid = model.grid_
    coords = [symbol(c) for c in grid.names]
    args = [symbol("t"), *coords]
    functions = {f: sp.Function(f)(*args) for f in model.field_names_}
    swap = {}
    for s in expr.free_symbols:
        if s.name in functions:
            swap[s] = functions[s.name]
            continue
        found = parse_derivative(s.name, model.field_names_, grid.names)
        if found:
            field, alpha = found
            swap[s] = sp.Derivative(functions[field], *[(c, a) for c, a in
                                                        zip(coords, alpha, strict=True) if a])
    return expr.xreplace(swap)


def to_latex(model, precision: int = 4, part=None) -> str:
    r"""The fitted PDE model's equations as a LaTeX ``aligned`` block, one ``u_t &= ...`` line
    per field with floats rounded to ``precision`` significant digits (see
    :meth:`~discrepancy.PDEDiscrepancyModel.to_latex`); a discrepancy alone is written
    ``\delta u_t``."""

    validate_params("to_latex", {"precision": precision},
                    {"precision": [Interval(Integral, 1, 17)]})
    exprs = to_sympy(model, part)
    lines = []
    discrepancy_only = part == "discrepancy" or (model.prior is not None
                                                 and not model.prior_.is_symbolic)
    for name, e in zip(model.field_names_, exprs, strict=True):
        rounded = e.xreplace({f: sp.Float(f, precision) for f in e.atoms(sp.Float)})
        lhs = ("\\delta " if discrepancy_only else "") + sp.latex(symbol(f"{name}_t"))
        lines.append(f"{lhs} &= {sp.latex(rounded) if e != 0 else '0'}")
    return "\\begin{aligned}\n" + " \\\\\n".join(lines) + "\n\\end{aligned}"
