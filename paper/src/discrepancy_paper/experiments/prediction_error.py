"""Prediction error against output error: a forced oscillator pushed by a force nobody
measured.

System (simulated): ``pos' = vel``, ``vel' = -pos - 0.1 vel + u`` (the prior) ``- 0.3 vel -
0.5 pos³`` (the discrepancy to find) ``+ d(t) + w(t)``: ``d`` is a push that jumps to a new
random level (std 0.5) every 15 s and is not in any model or measurement, ``w`` white
process noise of intensity 0.02 per √s. Only the position is measured (noise std 0.01), at
20 Hz for 300 s (6,000 samples); the input ``u`` (a sum of 12 sines up to 1 Hz) is held
over each sample. Both routes get the same data, the same library (every polynomial of
degree ≤ 3 in ``pos`` and ``vel``, acting on ``vel'``; ``pos'`` exact), the same input hold
and RK4 steps, and choose their terms by their own default procedure: ``fit_outputs``
(output error: free simulation from estimated initial states) and ``fit_prediction_error``
(the hybrid model inside an extended Kalman filter, told only that ``vel'`` may carry an
unmeasured disturbance; coefficients and noise levels from the innovations' likelihood).
"""
from __future__ import annotations

import time

import numpy as np

import discrepancy as dc
from discrepancy.runge_kutta import runge_kutta_step

from .prediction_error_settings import (  # noqa: F401 (the settings, read here by tests)
    DT,
    PROCESS_NOISE,
    PUSH_EVERY,
    PUSH_STD,
    SENSOR_NOISE,
    T_FULL,
    T_QUICK,
    TRUE,
)
from .report import Report

FIT = {"outputs": ["pos"], "u_hold": "zoh", "substeps": 2}
SEEDS_FULL, SEEDS_QUICK = (1, 2, 3, 4, 5), (1, 2, 3)


def true_rhs(x, u, push):
    """The simulated system's ``x'`` for states ``(m, 2)``, inputs and pushes ``(m,)``."""
    pos, vel = x[:, 0], x[:, 1]
    return np.column_stack((vel, -pos - 0.1 * vel + u - 0.3 * vel - 0.5 * pos ** 3 + push))


def record(seed: int, duration: float, *, push_std=PUSH_STD, process_noise=PROCESS_NOISE):
    """``(t, u, y, states, push)``: RK4 at 10 steps per sample with the input and push held,
    the process noise added as a velocity increment at each step (Euler–Maruyama)."""
    rng = np.random.default_rng(seed)
    m, fine = int(round(duration / DT)), 10
    t = np.arange(m) * DT
    freqs, phases = np.linspace(0.05, 1.0, 12), rng.uniform(0, 2 * np.pi, 12)
    u = 1.2 * np.sin(2 * np.pi * freqs * t[:, None] + phases).sum(axis=1) / np.sqrt(6)
    levels = push_std * rng.standard_normal(int(duration // PUSH_EVERY) + 2)
    levels[0] = 0.0
    push = levels[(t // PUSH_EVERY).astype(int)]
    x, h, states = np.zeros((1, 2)), DT / fine, np.empty((m, 2))

    def held(z, args):
        return true_rhs(z, *args)

    for k in range(m):
        states[k] = x[0]
        args = (u[k:k + 1], push[k:k + 1])
        for _ in range(fine):
            x = runge_kutta_step(held, x, h, args, args, args)
            x[0, 1] += process_noise * np.sqrt(h) * rng.standard_normal()
    y = states[:, :1] + SENSOR_NOISE * rng.standard_normal((m, 1))
    return t, u[:, None], y, states, push


def new_model(library=None, optimizer=None):
    pos, vel, u = (dc.symbolic.symbol(n) for n in ("pos", "vel", "u"))
    return dc.DiscrepancyModel(
        prior=[vel, -pos - 0.1 * vel + u], state_names=["pos", "vel"], input_names=["u"],
        feature_library=library or dc.PolynomialLibrary(3, variables=["pos", "vel"]),
        optimizer=optimizer, constraints=dc.Constraints(exact_equations=["pos"]))


def true_terms_model():
    """The library of the two true terms only, every coefficient kept (an oracle support)."""
    pos, vel = dc.symbolic.symbol("pos"), dc.symbolic.symbol("vel")
    return new_model(dc.CustomLibrary([vel, pos ** 3]), dc.STLSQ(threshold=1e-9))


def summary(model, seconds: float) -> dict:
    """Terms found against the true ones, coefficient errors (%), fit time."""
    names = model.get_feature_names()
    found = {names[j]: float(c) for j, c in enumerate(model.coef_[1]) if c != 0}
    errors = {n: 100 * (found[n] - v) / abs(v) for n, v in TRUE.items() if n in found}
    return {"terms_found": found, "coefficient_errors_percent": errors,
            "missed_terms": sorted(set(TRUE) - set(found)),
            "spurious_terms": sorted(set(found) - set(TRUE)),
            "right_terms": set(found) == set(TRUE),
            "max_abs_coefficient_error_percent": max((abs(e) for e in errors.values()),
                                                     default=float("nan")),
            "fit_cpu_seconds": seconds}


def fit_both(y, t, u, make=new_model) -> dict:
    out = {}
    for route in ("output_error", "prediction_error"):
        model, started = make(), time.process_time()
        if route == "output_error":
            model.fit_outputs(y, t, u=u, **FIT)
        else:
            model.fit_prediction_error(y, t, u=u, disturbances=["vel"], **FIT)
        out[route] = (model, summary(model, time.process_time() - started))
    return out


def validation_errors(models: dict, seed: int = 1000) -> tuple[dict, tuple]:
    """RMS simulation error of each model on a new record without push or process noise
    (new input), from the true initial state, and that record."""
    t, u, y, states, _ = record(seed, 60.0, push_std=0.0, process_noise=0.0)
    out = {}
    for name, model in models.items():
        sim = model.simulate(states[0], t, u=u, method="rk4", substeps=2, u_hold="zoh")
        out[name] = float(np.sqrt(np.mean((sim[:, 0] - states[:, 0]) ** 2)))
    return out, (t, states, {name: model.simulate(states[0], t, u=u, method="rk4",
                                                   substeps=2, u_hold="zoh")[:, 0]
                             for name, model in models.items()})


def run(out_dir, *, quick: bool = False):
    from .prediction_error_report import write

    rep = Report(out_dir, "prediction-error", title="Prediction error against output error: "
                 "an oscillator with process noise and an unmeasured push")
    duration = T_QUICK if quick else T_FULL
    t, u, y, states, push = record(0, duration)
    main = fit_both(y, t, u)
    seeds = {}
    for seed in SEEDS_QUICK if quick else SEEDS_FULL:
        data = record(seed, duration)
        seeds[seed] = {route: s for route, (_, s) in
                       fit_both(data[2], data[0], data[1], true_terms_model).items()}
    pem = main["prediction_error"][0]
    kf = pem.kalman_filter()
    smoothed, _ = kf.smooth(kf.filter(y, t, u=u))
    prior = pem.with_coefficients(np.zeros_like(pem.coef_))
    validation, curves = validation_errors({"prior alone": prior,
                                            "output error": main["output_error"][0],
                                            "prediction error": pem})
    write(rep, main, seeds, (t, u, y, states, push, smoothed), validation, curves, quick,
          intro=__doc__)
    return rep.write()

