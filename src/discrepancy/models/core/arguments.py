"""Argument conventions shared by the model's methods."""
from __future__ import annotations

from ...errors import ParameterError

#: the data arguments scikit-learn passes on to each fold when metadata routing is enabled
ROUTED = {"fit": ("t", "u", "x_dot", "sample_weight"), "score": ("t", "u", "x_dot")}
ROUTING_HINT = ("under scikit-learn cross-validation (GridSearchCV, cross_val_score) let t "
                "reach every fold's fit and score with "
                "sklearn.set_config(enable_metadata_routing=True); the model asks for t, u "
                "and x_dot by default")


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


def require_t(method: str, t, *, needed: bool) -> None:
    """PySINDy's ``fit(x, t)`` and ``score(x, t)`` need ``t``; so do ours whenever the times
    are used (a continuous-time model differentiating ``x`` or simulating). ``t=None`` is
    never read as a step of 1."""
    if t is None and needed:
        raise ParameterError(f"{method}: t is required (the time step, the sample times "
                             f"(m,), or a list of them per trajectory), as in PySINDy's "
                             f"{method}(x, t); a continuous-time model never assumes a step "
                             f"of 1. It may be left out when x_dot is given, or for a "
                             f"discrete-time model. Note: {ROUTING_HINT}")


def metadata_routing(owner: str):
    """scikit-learn's metadata request of a model: ``fit`` takes ``t``, ``u``, ``x_dot``,
    ``sample_weight`` and ``score`` takes ``t``, ``u``, ``x_dot`` from the caller, split per
    fold (scikit-learn is imported only when it asks)."""
    from sklearn.utils.metadata_routing import MetadataRequest

    request = MetadataRequest(owner=owner)
    for method, names in ROUTED.items():
        for name in names:
            getattr(request, method).add_request(param=name, alias=True)
    return request
