"""Models chosen blind, by forecasts, never silently worse than the prior.

Three simulated cases, every model fitted with the library's defaults (nothing tuned):

(a) exact priors: Van der Pol (the paper's system, prior alpha = truth) and a Duffing
    oscillator; the defaults should return the prior alone in every noise seed.
(b) a weak damping the prior lacks: the Duffing oscillator with ``-0.1 x2``; the defaults
    should find exactly that term.
(c) a disturbance the training data do not contain: a forced Duffing oscillator whose
    prior lacks its cubic spring and damping; the library is chosen blind by
    ``choose_procedure`` on training records, and the chosen hybrid forecasts a test
    record in which an unmeasured force kicks the oscillator beyond the training range;
    repeated over ``DISTURBANCE_SEEDS`` (inputs' phases and noise), the chosen hybrid's
    k-step errors on the disturbed record against the prior alone's.

Noise: Gaussian of standard deviation 0.1 on every state (10x the paper's 0.01), sampling
0.01, 25 time units per record, as the paper's Van der Pol data. For (a) and (b) the old
default (the equation-error choice: blocked cross-validation of the derivative fit and
the one-standard-error rule, ``selection="optimizer"``) is run on the same data.
"""
from __future__ import annotations

import warnings

import numpy as np
from scipy.integrate import solve_ivp

import discrepancy as dc

from .blind_selection_report import (
    HORIZONS,
    k_step_rms,
    report_cases,
    report_disturbance,
    report_disturbance_seeds,
)
from .report import Report

DT, DURATION, NOISE = 0.01, 25.0, 0.1
DAMPING = 0.1
METHODS = {"forecasts (default)": "auto", "equation error (old default)": "optimizer"}


def duffing(c: float = 0.0, cubic: float = 1.0):
    return lambda x, u=None: np.column_stack([x[:, 1],
                                              -x[:, 0] - cubic * x[:, 0] ** 3 - c * x[:, 1]])


def van_der_pol(alpha: float = 0.5):
    return lambda x, u=None: np.column_stack([x[:, 1],
                                              alpha * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]])


def simulate(rhs, x0, t, u=None):
    """Reference trajectory by scipy (DOP853, tolerances 1e-10); ``u(t)`` a callable."""
    f = (lambda s, z: rhs(z[None])[0]) if u is None else \
        (lambda s, z: rhs(z[None], np.atleast_2d(u(s)))[0])
    sol = solve_ivp(f, (t[0], t[-1]), x0, t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10)
    return sol.y.T


CASES = {
    "Van der Pol, exact prior": dict(true=van_der_pol(), prior=van_der_pol(), x0=[0.5, 0.0],
                                     truth=set()),
    "Duffing, exact prior": dict(true=duffing(), prior=duffing(), x0=[1.5, 0.0], truth=set()),
    "Duffing, weak damping missing": dict(true=duffing(DAMPING), prior=duffing(),
                                          x0=[1.5, 0.0], truth={("x2", "x2")}),
}


def fit_case(case, seeds, t):
    """Per method: the active terms of every seed, prior-only flags and CPU seconds."""
    import time

    x = simulate(case["true"], case["x0"], t)
    out = {m: {"terms": [], "prior_only": [], "cpu_s": 0.0, "damping": []} for m in METHODS}
    example = None
    for seed in seeds:
        noisy = x + NOISE * np.random.default_rng(seed).standard_normal(x.shape)
        for method, selection in METHODS.items():
            model = dc.DiscrepancyModel(prior=case["prior"],
                                        feature_library=dc.PolynomialLibrary(3),
                                        selection=selection)
            start = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model.fit(noisy, t=DT)
            out[method]["cpu_s"] += time.process_time() - start
            names = model.get_feature_names()
            terms = {(model.state_names_[i], names[j]): float(model.coef_[i, j])
                     for i, j in zip(*np.nonzero(model.coef_), strict=True)}
            out[method]["terms"].append(terms)
            out[method]["prior_only"].append(bool(model.prior_only_))
            out[method]["damping"].append(terms.get(("x2", "x2")))
            if example is None and selection == "auto":
                example = model
    return out, example


def run(out_dir, *, quick: bool = False):
    rep = Report(out_dir, "blind-selection",
                 title="Models chosen blind, by forecasts, never silently worse than the prior")
    seeds = range(3 if quick else 20)
    t = np.arange(0, DURATION + DT / 2, DT)
    rep.text(__doc__.split("\n", 1)[1].strip())
    cases = {name: fit_case(case, seeds, t) for name, case in CASES.items()}
    report_cases(rep, cases, CASES, seeds)
    shown = disturbance_case(quick=quick, seed=DISTURBANCE_SEEDS[0])   # also repeated below
    report_disturbance(rep, shown)
    report_disturbance_seeds(rep, [
        {"seed": s, **disturbance_errors(shown if s == DISTURBANCE_SEEDS[0] else
                                         disturbance_case(quick=quick, seed=s))}
        for s in DISTURBANCE_SEEDS[:2 if quick else None]])
    return rep.write()


# --------------------------------------------------------------------- (c) disturbance
TRUE_FORCED = dict(c=0.1, cubic=0.5, gain=1.0)
#: the unmeasured force of the test record (from t = 12 to 14)
PUSH = 2.0
#: seeds of the repeated disturbance case (inputs' phases and noise; 11 is the one shown)
DISTURBANCE_SEEDS = (11, 12, 13, 14, 15)


def forced(c, cubic, gain):
    return lambda x, u: np.column_stack([x[:, 1], -x[:, 0] - cubic * x[:, 0] ** 3 - c * x[:, 1]
                                         + gain * u[:, 0]])


def forcing(amplitude, frequencies, phase):
    return lambda s: np.array([amplitude * sum(np.sin(w * s + p) for w, p in
                                                 zip(frequencies, phase, strict=True))])


def disturbance_case(*, quick: bool, seed: int = 11):
    """Training: two records driven by a measured multisine; test: a third record with an
    unmeasured force pulse (amplitude 2 for 2 time units) the training never saw;
    ``seed``: the inputs' phases and the noise."""
    t = np.arange(0, DURATION + DT / 2, DT)
    rng = np.random.default_rng(seed)
    true = forced(**TRUE_FORCED)
    records = []
    for k in range(3):
        u = forcing(0.4, (0.7, 1.3, 2.1), rng.uniform(0, 2 * np.pi, 3))
        push = (lambda s: PUSH if 12.0 <= s < 14.0 else 0.0) if k == 2 else (lambda s: 0.0)
        x = simulate(true, [0.0, 0.0], t, u=lambda s, u=u, push=push: u(s) + push(s))
        u_measured = np.array([u(s) for s in t])     # the push is not measured
        noisy = x + NOISE * rng.standard_normal(x.shape)
        records.append((noisy, u_measured, x))
    train, test = records[:2], records[2]
    prior = forced(0.0, 0.0, 1.0)
    model = dc.DiscrepancyModel(prior=prior, state_names=["q", "v"], input_names=["u"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        choice = dc.choose_procedure(model, [r[0] for r in train], t=DT,
                                     u=[r[1] for r in train],
                                     **({"n_origins": 2} if quick else {}))
        old = dc.DiscrepancyModel(prior=prior, state_names=["q", "v"], input_names=["u"],
                                  feature_library=dc.PolynomialLibrary(3),
                                  selection="optimizer").fit(
            [r[0] for r in train], t=DT, u=[r[1] for r in train])
        prior_model = dc.DiscrepancyModel(prior=prior, state_names=["q", "v"],
                                          input_names=["u"], optimizer="prior_only").fit(
            [r[0] for r in train], t=DT, u=[r[1] for r in train])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        choice.model.predict_ahead(test[0], t, u=test[1], steps=50)
    guard = [str(w.message) for w in caught if issubclass(w.category,
                                                          dc.errors.ExtrapolationWarning)]
    models = {"prior alone": prior_model, f"chosen hybrid ({choice.chosen})": choice.model,
              "old default, polynomial 3": old}
    return dict(t=t, test=test, train=train, choice=choice, models=models, guard=guard,
                push=(12.0, 14.0))


def disturbance_errors(case) -> dict:
    """RMS errors of k-step forecasts (every horizon of the report) of the disturbed test
    record's noise-free states, from every measured (noisy) test state, for the prior alone
    and the chosen hybrid: ``{model: {horizon: {"whole test record", "during and after the
    push"}}}`` plus the chosen library."""
    chosen = next(k for k in case["models"] if k.startswith("chosen"))
    out = {"chosen_library": case["choice"].chosen}
    for label, name in (("prior alone", "prior alone"), ("chosen hybrid", chosen)):
        out[label] = {horizon: k_step_rms(case, name, k) for horizon, k in HORIZONS.items()}
    return out
