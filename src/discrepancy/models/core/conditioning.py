"""Identifiability of a fit's coefficients from the Gram statistics alone.

A fit solves the normal equations ``ΘᵀΘ ξ = Θᵀy``, whose condition number is the square of
``Θ``'s: columns nearly collinear on the data (a state that barely moves beside its square,
an input equal to a state, a duplicated column) leave their coefficients set by rounding.
Streamed and Dask fits never hold ``Θ``, so the check reads the Gram matrix: the condition
number of each equation's kept terms after equilibration (``D G D``, unit diagonal), and the
eigenvector of its smallest eigenvalue, whose large entries are the terms that trade off.
"""
from __future__ import annotations

import warnings

import numpy as np

from ...errors import IllConditionedWarning

#: condition number of the scaled Gram matrix above which coefficients are not determined
#: to 1e-6 relative (the normal equations lose about log10(condition) digits of 16)
LIMIT = 1e10


def collinear_terms(gram: np.ndarray, support: np.ndarray) -> tuple[float, np.ndarray]:
    """``(condition, terms)`` of the columns ``support`` (``(p,)`` bool) of ``gram``
    ``(p, p)``: the condition number of their unit-diagonal Gram matrix (``inf`` when
    singular) and the indices of the terms that make it (entries of the smallest
    eigenvalue's eigenvector at least a tenth of its largest)."""
    index = np.flatnonzero(support)
    if len(index) < 2:
        return 1.0, index[:0]
    g = gram[np.ix_(index, index)]
    d = np.sqrt(np.diag(g))
    if np.any(d == 0):
        return np.inf, index[d == 0]
    values, vectors = np.linalg.eigh(g / np.outer(d, d))
    condition = np.inf if values[0] <= 0 else float(values[-1] / values[0])
    weight = np.abs(vectors[:, 0])
    return condition, index[weight >= 0.1 * weight.max()]


def warn_if_ill_conditioned(gram: np.ndarray, coef: np.ndarray, feature_names,
                            state_names, stacklevel: int = 3) -> dict:
    """Warn (:class:`~discrepancy.errors.IllConditionedWarning`) for every equation whose
    kept terms (nonzero entries of ``coef`` ``(n, p)``) have a scaled Gram condition number
    above :data:`LIMIT`; returns ``{state: condition}`` of every equation with two or more
    terms (the fitted model's ``conditioning_``)."""
    found, report = [], {}
    for name, row in zip(state_names, coef, strict=True):
        if np.count_nonzero(row) < 2:
            continue
        condition, terms = collinear_terms(gram, row != 0)
        report[name] = condition
        if condition > LIMIT:
            named = ", ".join(feature_names[j] for j in terms)
            found.append(f"the equation of {name} (terms {named}: condition number "
                         f"{condition:.2g})")
    if found:
        warnings.warn("nearly collinear terms on these data, whose coefficients the data do "
                      "not determine (a split between them is arbitrary, to about condition "
                      "x 1e-16 relative): " + "; ".join(found) + ". Drop one of each group, "
                      "excite the system more, or rescale the variables",
                      IllConditionedWarning, stacklevel=stacklevel)
    return report
