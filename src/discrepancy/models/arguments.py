"""Argument conventions shared by the model's methods."""
from __future__ import annotations

from ..errors import ParameterError


def keywords_only(method: str, extra: tuple, names: str) -> None:
    """Refuse positional arguments after ``t`` (PySINDy orders them differently, so a
    positional call would silently mean something else)."""
    if extra:
        first = "x0" if method.startswith("simulate") else "x"
        why = (" PySINDy's order is fit(x, t, x_dot, u), so a positional x_dot would "
               "otherwise be taken as u") if "x_dot" in names else ""
        raise ParameterError(f"{method}: arguments after t ({names}) must be passed by name, "
                             f"e.g. {method}({first}, t, u=u); got {len(extra)} more "
                             f"positional argument(s).{why}")
