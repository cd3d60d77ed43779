"""Exact export of a fitted model to sympy, LaTeX and CasADi."""
from __future__ import annotations

import sympy as sp

from ..._optional import require
from ...constraints import Integral, Interval, Options, check_argument, validate_params
from ...errors import ExportError
from ...symbolic import feature_name, symbol
from ...symbolic import to_casadi as expression_to_casadi
from ..core.uncertainty import check_uncertainty


def exported_part(model, part, *, default_hybrid: bool = False):
    """Which equations to export. By default the hybrid model when the prior is symbolic
    (or absent), else the discrepancy alone; ``default_hybrid`` makes the default the
    hybrid model always, so a callable prior is refused rather than silently dropped."""
    if part is None:
        symbolic = model.prior_.is_symbolic or model.prior is None
        part = "hybrid" if symbolic or default_hybrid else "discrepancy"
    check_argument("part", part, Options(("hybrid", "discrepancy")))
    if part == "hybrid" and model.prior is not None and not model.prior_.is_symbolic:
        raise ExportError("the prior is a Python callable, so the hybrid model has no exact "
                          "symbolic form; pass the prior as sympy expressions, or ask for "
                          "part='discrepancy'")
    return part


def discrepancy_expressions(model) -> list[sp.Expr]:
    """``g_i = Σ_j ξ_ij θ_j`` for each state, with the fitted float coefficients."""
    model.check_is_fitted()
    return [sp.Add(*[sp.Float(c) * e for c, e in zip(row, model.feature_expressions_,
                                                       strict=True) if c != 0])
            for row in model.coef_]


def to_sympy(model, part=None) -> list[sp.Expr]:
    """The model's right-hand sides as sympy expressions (see
    :meth:`~discrepancy.DiscrepancyModel.to_sympy`)."""
    part = exported_part(model, part)
    g = discrepancy_expressions(model)
    if part == "discrepancy" or not model.prior_.is_symbolic:
        return g
    return [f + gi for f, gi in zip(model.prior_.expressions, g, strict=True)]


def to_latex(model, precision: int = 4, part=None) -> str:
    """The model's equations as LaTeX (see :meth:`~discrepancy.DiscrepancyModel.to_latex`);
    a map's left-hand sides are ``x[k+1]``, an ODE's ``\\dot{x}``."""

    validate_params("to_latex", {"precision": precision},
                    {"precision": [Interval(Integral, 1, 17)]})
    exprs = to_sympy(model, part)
    lines = []
    for name, e in zip(model.state_names_, exprs, strict=True):
        rounded = e.xreplace({f: sp.Float(f, precision) for f in e.atoms(sp.Float)})
        lhs = sp.latex(symbol(name)) + "[k+1]" if model.discrete_time else \
            r"\dot{" + sp.latex(symbol(name)) + "}"
        rhs = sp.latex(rounded) if e != 0 else "0"
        if part == "discrepancy" or (model.prior is not None and not model.prior_.is_symbolic):
            lhs = r"\delta " + lhs
        lines.append(f"{lhs} &= {rhs}")
    return "\\begin{aligned}\n" + " \\\\\n".join(lines) + "\n\\end{aligned}"


def to_casadi(model, part=None):
    """CasADi Function ``f(x, u) -> xdot`` built from the sympy form (only active terms);
    a discrete-time model's output is named ``x_next`` (the map, not a rate)."""

    ca = require("casadi", purpose="to_casadi")

    part = exported_part(model, part, default_hybrid=True)
    x = ca.SX.sym("x", model.n_states_)
    u = ca.SX.sym("u", model.n_inputs_)
    variables = {n: x[i] for i, n in enumerate(model.state_names_)}
    variables.update({n: u[i] for i, n in enumerate(model.input_names_)})
    rows = []
    for i in range(model.n_states_):
        total = 0
        for c, e in zip(model.coef_[i], model.feature_expressions_, strict=True):
            if c != 0:
                name = feature_name(e, model.variable_names_)
                total = total + float(c) * expression_to_casadi(e, variables, term=name)
        if part == "hybrid" and model.prior_.is_symbolic:
            total = total + expression_to_casadi(model.prior_.expressions[i], variables,
                                                 term=f"prior[{i}]")
        rows.append(total)
    xdot = ca.vertcat(*[ca.SX(r) if not isinstance(r, ca.SX) else r for r in rows])
    out = "x_next" if model.discrete_time else "xdot"
    if model.n_inputs_ == 0:
        return ca.Function("f", [x], [xdot], ["x"], [out])
    return ca.Function("f", [x, u], [xdot], ["x", "u"], [out])


def equations(model, precision: int = 3, uncertainty=None) -> list[str]:
    """Right-hand sides as text, e.g. ``prior + 0.400 x2 - 0.400 x1^2 x2``, one per state;
    with ``uncertainty``, coefficients as ``(0.400 ± 0.004)``. Every non-zero coefficient is
    shown: one that rounds to 0 at ``precision`` decimals as ``1.95e-04``."""

    validate_params("equations", {"precision": precision},
                    {"precision": [Interval(Integral, 0, 16)]})
    names = model.get_feature_names()
    std = None
    if uncertainty is not None:
        check_uncertainty(model, uncertainty)
        std = uncertainty.std
    out = []
    for i, row in enumerate(model.coef_):
        parts = [] if model.prior is None else ["prior"]
        for j, (c, name) in enumerate(zip(row, names, strict=True)):
            if c != 0:
                size = _number(abs(c), c, precision)
                if std is not None:
                    size = f"({size} ± {_number(std[i, j], c, precision)})"
                term = size + ("" if name == "1" else f" {name}")
                parts.append(("- " if c < 0 else "+ ") + term if parts else
                             ("-" if c < 0 else "") + term)
        out.append(" ".join(parts) if parts else f"{0:.{precision}f}")
    return out


def _number(value: float, coef: float, precision: int) -> str:
    """``value`` with ``precision`` decimals, or, when the coefficient ``coef`` it belongs to
    would print as 0 that way, with ``precision`` significant digits (``1.95e-04``): a small
    coefficient of a large term (``u`` of hundreds of newtons) is not negligible, and PySINDy,
    which leaves such terms out, hides them."""
    if round(abs(coef), precision) != 0:
        return f"{value:.{precision}f}"
    return f"{value:.{max(precision - 1, 0)}e}"


def choice_line(model) -> str:
    """``# derivatives: <method>, chosen by GCV from the data; noise std ≈ [...]`` for a
    model whose differentiation was chosen from the data (else ``""``)."""
    choice = getattr(model, "differentiation_choice_", None)
    if not choice:
        return ""
    line = f"# derivatives: {model.differentiation_method_!r}, chosen by {choice['chosen_by']}"
    if "noise_std" not in choice:  # a fallback for short records estimates no noise
        return line
    noise = ", ".join(f"{v:.3g}" for v in choice["noise_std"])
    return f"{line} from the data; noise std of the states ≈ [{noise}]"
