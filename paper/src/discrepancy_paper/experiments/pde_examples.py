"""PDE discrepancy models: Burgers with a wrong viscosity, a reaction-diffusion system
missing its reaction, Kuramoto-Sivashinsky missing a term; ours beside PySINDy.

Each example simulates the true PDE (spectral ETDRK4, ``rtol`` 1e-9), adds Gaussian noise
of a given fraction of the field's standard deviation, and fits:

* ours, defaults only, with the flawed prior: the discrepancy ``g`` it learns;
* ours, defaults only, without prior: the whole right-hand side (PySINDy's task);
* PySINDy's weak form and PDE-FIND on the whole right-hand side, with our default library
  and a threshold set from the true coefficients (half the smallest): a choice made
  knowing the answer, which favours PySINDy (ours uses no such knowledge);
* on clean data, PDE-FIND in our implementation with PySINDy's settings exactly (no prior,
  finite differences in time, spectral in space, that threshold): equal coefficients.

Coefficient errors are relative to the true coefficient of each term (a missing term
counts 100 %), for the discrepancy (ours) or the whole equation (the others; the
discrepancy they imply is their coefficient minus the prior's and is reported too).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

import discrepancy as dc
from discrepancy.pde.variables import FieldVariables
from discrepancy.symbolic import feature_name, symbol

from . import pde_pysindy
from .pde_report import write_report

S = {n: symbol(n) for n in "u v u_x u_xx u_yy u_xxxx v_xx v_yy".split()}
#: the true PDE's tolerance in quick (test) runs: the experiments' 1e-9 costs 2-3 times the
#: CPU and moves the quick runs' coefficient errors by 1e-7 of themselves
QUICK_RTOL = 1e-7


@dataclass
class Example:
    """One example: the true PDE, the prior, the grid and the sampling."""

    name: str
    title: str
    truth: list
    prior: list
    grid: dc.Grid
    u0: np.ndarray
    t: np.ndarray
    fields: list = field(default_factory=lambda: ["u"])
    noise: tuple = (0.0, 0.01, 0.05)
    seeds: int = 2
    order: int = 2          # the derivative order of the default library (for PySINDy)
    #: False (quick runs, for tests): the whole-equation fits (ours without prior, PySINDy's)
    #: on clean data only
    whole_equation_on_noisy_data: bool = True
    #: share of the record the forecast from the initial field covers (quick runs: a quarter)
    forecast_share: float = 0.5
    #: PySINDy's fits run (quick runs: PDE-FIND alone, which the parity check needs)
    peers: tuple = ("weak", "pde-find")
    #: relative tolerance of the true PDE's simulation (quick runs: QUICK_RTOL)
    rtol: float = 1e-9


def burgers(quick: bool, full: bool) -> Example:
    n, end = (128, 8.0) if quick else (256, 10.0)
    x = np.linspace(-8, 8, n, endpoint=False)
    u, ux, uxx = S["u"], S["u_x"], S["u_xx"]
    return Example("pde-burgers", "Burgers with a wrong viscosity (prior nu = 0.05, true 0.1)",
                   [-u * ux + 0.1 * uxx], [-u * ux + 0.05 * uxx], dc.Grid(x, periodic=True),
                   np.exp(-(x + 2) ** 2), np.arange(0, end + 1e-9, 0.1),
                   noise=(0.0, 0.01, 0.05, 0.1) if full else (0.0, 0.01, 0.05),
                   seeds=10 if full else (1 if quick else 2), order=4,
                   whole_equation_on_noisy_data=not quick,
                   forecast_share=0.25 if quick else 0.5,
                   peers=("pde-find",) if quick else ("weak", "pde-find"),
                   rtol=QUICK_RTOL if quick else 1e-9)


def reaction_diffusion(quick: bool, full: bool) -> Example:
    n = 32 if quick else (64 if full else 48)
    x = np.linspace(-10, 10, n, endpoint=False)
    grid = dc.Grid(x, x, periodic=True)
    a, b = grid.mesh()
    r, theta = np.hypot(a, b), np.arctan2(b, a)
    u0 = np.stack([np.tanh(r * np.cos(theta - r)), np.tanh(r * np.sin(theta - r))], axis=-1)
    u, v = S["u"], S["v"]
    lap_u, lap_v = S["u_xx"] + S["u_yy"], S["v_xx"] + S["v_yy"]
    square = u ** 2 + v ** 2
    truth = [0.1 * lap_u + (1 - square) * u + square * v,
             0.1 * lap_v - square * u + (1 - square) * v]
    return Example("pde-reaction-diffusion", "Reaction-diffusion (lambda-omega) in 2-D, the "
                   "prior misses the whole reaction", truth, [0.1 * lap_u, 0.1 * lap_v], grid,
                   u0, np.arange(0, (5.0 if quick else 10.0) + 1e-9, 0.1 if not full else 0.05),
                   fields=["u", "v"], seeds=4 if full else 1, order=2,
                   whole_equation_on_noisy_data=not quick,
                   forecast_share=0.25 if quick else 0.5,
                   peers=("pde-find",) if quick else ("weak", "pde-find"),
                   rtol=QUICK_RTOL if quick else 1e-9)


def kuramoto_sivashinsky(quick: bool, full: bool) -> Example:
    x = np.linspace(0, 32 * np.pi, 128, endpoint=False)
    u, ux, uxx, uxxxx = S["u"], S["u_x"], S["u_xx"], S["u_xxxx"]
    return Example("pde-kuramoto-sivashinsky", "Kuramoto-Sivashinsky, the prior misses -u_xx",
                   [-u * ux - uxx - uxxxx], [-u * ux - uxxxx], dc.Grid(x, periodic=True),
                   np.cos(x / 16) * (1 + np.sin(x / 16)),
                   np.arange(0, (50.0 if quick else 100.0) + 1e-9, 0.25),
                   noise=(0.0, 0.01, 0.05, 0.1) if full else (0.0, 0.01, 0.05),
                   seeds=10 if full else (1 if quick else 2), order=4,
                   whole_equation_on_noisy_data=not quick,
                   forecast_share=0.25 if quick else 0.5,
                   peers=("pde-find",) if quick else ("weak", "pde-find"),
                   rtol=QUICK_RTOL if quick else 1e-9)


def coefficients(example, expressions) -> dict:
    """``{field: {term name: coefficient}}`` of sympy right-hand sides in jet symbols,
    named as the models name their columns."""
    names = FieldVariables(tuple(example.fields), example.grid.names, (), 4).names
    out = {}
    for f, e in zip(example.fields, expressions, strict=True):
        terms = {}
        for term in sp.Add.make_args(sp.expand(e)):
            c, body = term.as_coeff_Mul()
            terms[feature_name(body, names)] = float(c)
        out[f] = terms
    return out


def errors(found: dict, truth: dict) -> dict:
    """Support right, per-term errors (%), and the largest, of found against true terms."""
    right = all(set(found.get(f, {})) == set(truth[f]) for f in truth)
    per = {f"{f}: {k}": 100 * abs(found[f].get(k, 0.0) - v) / abs(v)
           for f in truth for k, v in truth[f].items()}
    return {"terms_right": right, "coefficient_errors_percent": per,
            "max_coefficient_error_percent": max(per.values()),
            "found_terms": found}


def ours(example, U, *, prior) -> dict:
    model = dc.PDEDiscrepancyModel(prior=example.prior if prior else None,
                                   field_names=example.fields)
    start = time.process_time()
    model.fit(U, t=example.t[1] - example.t[0], grid=example.grid)
    seconds = time.process_time() - start
    names = model.get_feature_names()
    found = {f: {names[j]: float(model.coef_[i, j]) for j in np.flatnonzero(model.coef_[i])}
             for i, f in enumerate(example.fields)}
    choice = model.differentiation_choice_ or {}
    return {"found": found, "fit_seconds": seconds, "model": model,
            "form": choice.get("form"), "widths": choice.get("widths")}


def implied_discrepancy(found: dict, prior: dict) -> dict:
    """A whole-equation model's coefficients minus the prior's (the correction it implies)."""
    out = {}
    for f in found:
        terms = {k: found[f].get(k, 0.0) - prior[f].get(k, 0.0)
                 for k in set(found[f]) | set(prior[f])}
        out[f] = {k: v for k, v in terms.items() if abs(v) > 1e-12}
    return out


def run_example(example: Example, out_dir) -> object:
    start = time.perf_counter()
    truth_model = dc.PDEDiscrepancyModel.prior_only(example.truth, example.grid,
                                                    field_names=example.fields)
    U = truth_model.simulate(example.u0, example.t, rtol=example.rtol)
    simulated = time.perf_counter() - start
    whole = coefficients(example, example.truth)
    prior = coefficients(example, example.prior)
    g_true = implied_discrepancy(whole, prior)
    threshold = 0.5 * min(abs(c) for f in whole.values() for c in f.values())
    rows, kept, clean_pde_find = [], {}, None
    for noise in example.noise:
        for seed in range(1 if noise == 0 else example.seeds):
            rng = np.random.default_rng(1000 + seed)
            noisy = U + noise * U.std() * rng.standard_normal(U.shape)
            mine = ours(example, noisy, prior=True)
            kept.setdefault(noise, (noisy, mine["model"]))
            rows.append({"noise_percent": 100 * noise, "seed": seed, "method": "ours (prior)",
                         "fit_seconds": mine["fit_seconds"], "form": mine["form"],
                         **errors(mine["found"], g_true)})
            if noise > 0 and not example.whole_equation_on_noisy_data:
                continue
            plain = ours(example, noisy, prior=False)
            rows.append({"noise_percent": 100 * noise, "seed": seed,
                         "method": "ours (no prior)", "fit_seconds": plain["fit_seconds"],
                         "form": plain["form"], **errors(plain["found"], whole),
                         "implied_discrepancy": errors(implied_discrepancy(
                             plain["found"], prior), g_true)})
            for kind in example.peers:
                ps_fit = pde_pysindy.fit(kind, noisy, example.t, example.grid,
                                         field_names=example.fields, degree=3,
                                         order=example.order, threshold=threshold,
                                         include_bias=True)
                if noise == 0 and kind == "pde-find":
                    clean_pde_find = ps_fit     # the parity check's PySINDy fit, done once
                rows.append({"noise_percent": 100 * noise, "seed": seed,
                             "method": f"PySINDy {kind}", "fit_seconds": ps_fit["fit_seconds"],
                             **errors(ps_fit["coefficients"], whole),
                             "implied_discrepancy": errors(implied_discrepancy(
                                 ps_fit["coefficients"], prior), g_true)})
    parity = pde_find_parity(example, U, threshold, theirs=clean_pde_find)
    return write_report(example, out_dir, U=U, rows=rows, kept=kept, whole=whole, prior=prior,
                        g_true=g_true, threshold=threshold, parity=parity,
                        simulated_seconds=simulated, truth_model=truth_model)


def pde_find_parity(example, U, threshold, theirs=None) -> dict:
    """PDE-FIND with PySINDy's settings in both libraries, clean data: coefficient gap
    (``theirs``: PySINDy's fit of ``U`` with these settings, when already made)."""
    mine = dc.PDEDiscrepancyModel(
        feature_library=dc.PDELibrary(dc.PolynomialLibrary(3, include_bias=False),
                                      example.order, include_bias=True),
        optimizer=dc.STLSQ(threshold=threshold, alpha=1e-5),
        differentiation_method=dc.FiniteDifference(), spatial_differentiation="spectral",
        field_names=example.fields)
    start = time.process_time()
    mine.fit(U, t=example.t[1] - example.t[0], grid=example.grid)
    ours_seconds = time.process_time() - start
    theirs = theirs or pde_pysindy.fit("pde-find", U, example.t, example.grid,
                                       field_names=example.fields, degree=3,
                                       order=example.order, threshold=threshold,
                                       include_bias=True)
    names = mine.get_feature_names()
    gap = 0.0
    for i, f in enumerate(example.fields):
        other = theirs["coefficients"][f]
        for j, name in enumerate(names):
            gap = max(gap, abs(mine.coef_[i, j] - other.get(name, 0.0)))
    return {"max_coefficient_difference": gap, "ours_fit_seconds": ours_seconds,
            "pysindy_fit_seconds": theirs["fit_seconds"],
            "same_terms": all(set(theirs["coefficients"][f]) == {
                names[j] for j in np.flatnonzero(mine.coef_[i])}
                for i, f in enumerate(example.fields))}


def run_burgers(out_dir, *, quick: bool = False, full: bool = False):
    return run_example(burgers(quick, full), out_dir)


def run_reaction_diffusion(out_dir, *, quick: bool = False, full: bool = False):
    return run_example(reaction_diffusion(quick, full), out_dir)


def run_kuramoto_sivashinsky(out_dir, *, quick: bool = False, full: bool = False):
    return run_example(kuramoto_sivashinsky(quick, full), out_dir)
