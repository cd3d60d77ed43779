"""Default variable names, and the one way they could be misread.

The states are called ``x1 ... xn`` and the inputs ``u`` (one) or ``u1 ... ur`` by default:
the paper's names, and every example's. PySINDy counts from zero (``x0, x1, ...``), so a
PySINDy user's ``"x1"`` is the *second* state, which here is ``x2``. Where names are only
printed this is harmless; where the user refers to a variable by name (``Constraints``, a
library's ``variables=``) it would silently mean another equation. So a reference by name to
a default name is checked here: ``x0``/``u0`` (a 0-based name) is refused with an
explanation, and a name that exists in both conventions with different meanings (``xk`` for
``1 <= k < n``) gives a :class:`~discrepancy.errors.NameConventionWarning`. Naming the
variables (``state_names=``, ``input_names=``, or PySINDy's ``fit(feature_names=...)``)
makes every name explicit and silences it.
"""
from __future__ import annotations

import re
import warnings

from ...errors import NameConventionWarning, UnknownNameError

IDENTIFIERS = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def referenced_names(constraints, library) -> set[str]:
    """Every identifier a user wrote in ``constraints`` or in a library's ``variables``."""
    texts = []
    if constraints is not None:
        texts += list(constraints.exact_equations)
        for term, states in (constraints.only or {}).items():
            texts += [term, *states]
        for spec in (*constraints.equal, *constraints.at_most, *constraints.at_least):
            for key in spec[0]:
                texts += list(key)
    for key, value in library.get_params(deep=True).items():
        if key.split("__")[-1] == "variables" and isinstance(value, (list, tuple)):
            texts += [v for v in value if isinstance(v, str)]
    return {name for text in texts if isinstance(text, str) for name in IDENTIFIERS.findall(text)}


def check_default_names(referenced: set[str], states, inputs, *, default_states: bool,
                        default_inputs: bool) -> None:
    """Refuse 0-based names and warn about names whose meaning differs from PySINDy's, for
    the variables that have default names (see the module docstring)."""
    stems = [("x", len(states))] if default_states else []
    if default_inputs and len(inputs) > 1:
        stems.append(("u", len(inputs)))
    for stem, k in stems:
        if f"{stem}0" in referenced:
            raise UnknownNameError(
                f"{stem}0 is not a variable: the default names here start at {stem}1 (the "
                f"paper's {stem}1, {stem}2, ...; {stem}1 is the first), PySINDy's at {stem}0. "
                f"Refer to PySINDy's {stem}0 as {stem}1, or name the variables yourself "
                f"(state_names=/input_names=, or fit(feature_names=[...]), e.g. PySINDy's "
                f"{', '.join(f'{stem}{i}' for i in range(min(k, 3)))}, ...)")
        shared = sorted(n for n in referenced if re.fullmatch(rf"{stem}[1-9][0-9]*", n)
                        and int(n[1:]) < k)
        if shared:
            warnings.warn(
                f"{', '.join(shared)} refer(s) to default names, which start at {stem}1 (the "
                f"first variable); in PySINDy's names, which start at {stem}0, the same "
                f"name is the next variable. Give state_names=/input_names= (or "
                f"fit(feature_names=...)) to make the names explicit and silence this",
                NameConventionWarning, stacklevel=5)
