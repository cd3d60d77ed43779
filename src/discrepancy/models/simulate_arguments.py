"""PySINDy's ways of choosing a simulation's integrator, mapped onto the options of
:func:`~discrepancy.models.simulation.integrate`.

PySINDy's ``simulate(x0, t, u, integrator="solve_ivp", integrator_kws={...},
interpolator=..., interpolator_kws={...})`` passes ``integrator_kws`` to scipy's
``solve_ivp`` (whose default method is RK45) or ``odeint``; its defaults are LSODA at
``rtol = atol = 1e-12``, and ``odeint`` with those defaults runs at odeint's own tolerances.
The same calls mean the same solver and tolerances here; our own flat keywords
(``method=``, ``rtol=``, ...) stay the shorter spelling.
"""
from __future__ import annotations

from ..errors import ParameterError, describe

INTEGRATORS = ("solve_ivp", "odeint")
#: PySINDy's default integrator_kws
PYSINDY_DEFAULTS = {"method": "LSODA", "rtol": 1e-12, "atol": 1e-12}
#: scipy's odeint tolerances (used when PySINDy would pass it none)
ODEINT_TOLERANCE = 1.49012e-8


def integrator_options(integrator, integrator_kws, options: dict) -> dict:
    """``integrate``'s keyword options from PySINDy's ``integrator`` and ``integrator_kws``
    and our flat ``options`` (which may not repeat a key of ``integrator_kws``)."""
    if integrator is None and integrator_kws is None:
        return options
    if integrator is None:
        integrator = "solve_ivp"
    if not isinstance(integrator, str) or integrator not in INTEGRATORS:
        raise ParameterError(f"integrator must be one of {', '.join(map(repr, INTEGRATORS))} "
                             f"(or None: our stepped solvers, method=...); got "
                             f"{integrator!r}")
    if integrator_kws is not None and not isinstance(integrator_kws, dict):
        raise ParameterError(f"integrator_kws must be a dict of options; got "
                             f"{describe(integrator_kws)}")
    kws = dict(PYSINDY_DEFAULTS if integrator_kws is None else integrator_kws)
    both = sorted(set(kws) & set(options))
    if both:
        raise ParameterError(f"simulate got {both} both in integrator_kws and as keywords; "
                             "give each option once")
    if integrator == "odeint":
        if kws.get("method") == "LSODA":   # PySINDy's defaults mean odeint's own tolerances
            kws = {}
        if "method" in kws:
            raise ParameterError(f"integrator='odeint' takes no method (it is LSODA); got "
                                 f"method={kws['method']!r}")
        kws = {"rtol": ODEINT_TOLERANCE, "atol": ODEINT_TOLERANCE, **kws, "method": "odeint"}
    else:
        kws.setdefault("method", "RK45")   # solve_ivp's default
    return {**kws, **options}


def interpolated_input(u, t, interpolator, interpolator_kws):
    """``u`` as PySINDy's ``interpolator(t, u, **interpolator_kws)`` makes it a function of
    time (``u`` an array sampled at ``t``); unchanged without an interpolator."""
    if interpolator is None:
        if interpolator_kws:
            raise ParameterError("interpolator_kws were given without an interpolator")
        return u
    if not callable(interpolator):
        raise ParameterError(f"interpolator must be a callable interpolator(t, u, **kws) -> "
                             f"u(t), e.g. scipy.interpolate.interp1d; got "
                             f"{describe(interpolator)}")
    if u is None or callable(u):
        raise ParameterError("interpolator is for u given as samples at t (an array); "
                             f"got {describe(u)}")
    law = interpolator(t, u, **(interpolator_kws or {}))
    if not callable(law):
        raise ParameterError(f"interpolator(t, u) must return a callable u(t); got "
                             f"{describe(law)}")
    return law


def map_options(stop_condition, pysindy: dict, options: dict):
    """A discrete-time model's only option, ``stop_condition``; anything else is refused
    (a map has no integrator, and an ignored keyword would be a silent typo)."""
    given = {k for k, v in pysindy.items() if v is not None} | set(options)
    if given:
        raise ParameterError(f"simulate of a discrete-time model takes x0, t (steps), u and "
                             f"stop_condition; got {sorted(given)}")
    return stop_condition


def simulation_options(u, t, stop_condition, pysindy: dict, options: dict):
    """``(u, options)`` for :func:`~discrepancy.models.simulation.integrate` from PySINDy's
    keywords and ours, checked before any work that depends on them."""
    from .simulation import check_options

    if stop_condition is not None:
        raise ParameterError("stop_condition is for discrete-time models (as in PySINDy); a "
                             "continuous simulation runs over all of t")
    kws = integrator_options(pysindy["integrator"], pysindy["integrator_kws"], options)
    u = interpolated_input(u, t, pysindy["interpolator"], pysindy["interpolator_kws"])
    check_options(kws)
    return u, kws
