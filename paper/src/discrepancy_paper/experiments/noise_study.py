"""Where each way of fitting breaks as noise grows: the no-tuning defaults, the paper's
settings, the weak form, and PySINDy 2.x (its defaults, and its weak library), on the same
noisy data with a wrong prior.

Van der Pol (prior alpha 0.1, truth 0.5; discrepancy ``0.4 x2 - 0.4 x1^2 x2``) and Lorenz
(prior rho 20, truth 28; discrepancy ``8 x1`` in the second equation). Noise is Gaussian, a
fraction of each state's standard deviation. PySINDy gets the residual of the prior as its
target: its default finite differences minus ``f_m(x)``; with its weak library, the weak
derivative minus ``f_m`` integrated by the same library against the same test functions.
Both get our library's columns (same names, same order), so only differentiation and
selection differ.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from tqdm import tqdm

import discrepancy as dc
from discrepancy.systems import VanDerPol

from .report import Report

LEVELS = (0.0, 0.01, 0.02, 0.05, 0.1, 0.2)
METHODS = ("defaults", "paper settings", "weak form", "PySINDy defaults", "PySINDy weak")
#: methods whose fit depends on the data alone (PySINDy's weak library draws its sub-domains
#: from numpy's global generator, so its noise-free seeds differ)
DETERMINISTIC = METHODS[:4]
#: a quick (test) run: our defaults and PySINDy's, the pair its test checks against the truth
#: (the weak fits and the paper's settings were half its CPU)
QUICK_METHODS = ("defaults", "PySINDy defaults")


def _lorenz(x, u=None, rho=28.0):
    x = np.atleast_2d(x)
    return np.column_stack([10 * (x[:, 1] - x[:, 0]), x[:, 0] * (rho - x[:, 2]) - x[:, 1],
                            x[:, 0] * x[:, 1] - 8 / 3 * x[:, 2]])


def systems() -> dict[str, dict]:
    vdp = VanDerPol()
    return {
        "Van der Pol": {"rhs": vdp.rhs, "prior": vdp.flawed_model("parameter"),
                        "x0": [0.5, 0.0], "dt": 0.01, "steps": 2500, "degree": 3,
                        "truth": {(1, "x2"): 0.4, (1, "x1^2 x2"): -0.4}},
        "Lorenz": {"rhs": _lorenz, "prior": lambda x, u=None: _lorenz(x, rho=20.0),
                   "x0": [-8.0, 8.0, 27.0], "dt": 0.002, "steps": 5000, "degree": 2,
                   "truth": {(1, "x1"): 8.0}},
    }


def _truth(system) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(system["steps"] + 1) * system["dt"]
    sol = solve_ivp(lambda _, x: system["rhs"](x[None])[0], (0, t[-1]), system["x0"],
                    t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    return t, sol.y.T


def _ours(method, system, x, dt):
    options = {"defaults": {}, "weak form": {"differentiation_method": "weak"},
               "paper settings": {"differentiation_method": dc.SavitzkyGolay(31, 3),
                                  "optimizer": dc.STLSQ(threshold=0.05)}}[method]
    model = dc.DiscrepancyModel(prior=system["prior"],
                                feature_library=dc.PolynomialLibrary(system["degree"]),
                                **options).fit(x, t=dt)
    return model.coef_


def _pysindy(method, system, x, t):
    """PySINDy 2.x on the prior's residual; ``(n, p)`` in our column order."""
    import pysindy as ps

    n, degree, prior = x.shape[1], system["degree"], system["prior"]
    if method == "PySINDy defaults":
        target = ps.FiniteDifference()._differentiate(x, t) - prior(x)
        theta = ps.PolynomialLibrary(degree=degree).fit_transform(x)
    else:
        components = [_prior_component(prior, i, n) for i in range(n)]
        names = [_prior_name(i, n) for i in range(n)]
        lib = ps.WeakPDELibrary(function_library=ps.PolynomialLibrary(degree=degree)
                                + ps.CustomLibrary(library_functions=components,
                                                   function_names=names),
                                spatiotemporal_grid=t)
        weak = np.asarray(lib.fit_transform(x))
        p = weak.shape[1] - n
        theta, target = weak[:, :p], np.asarray(lib.convert_u_dot_integral(x)) - weak[:, p:]
    opt = ps.STLSQ()
    opt.fit(np.asarray(theta), np.asarray(target))
    return np.asarray(opt.coef_)


def _prior_component(prior, i, n):
    """Component ``i`` of the prior as a function of the ``n`` state columns (PySINDy's
    CustomLibrary reads the number of arguments from the signature)."""
    def two(a, b):
        return prior(np.column_stack([np.asarray(a), np.asarray(b)]))[:, i]

    def three(a, b, c):
        return prior(np.column_stack([np.asarray(v) for v in (a, b, c)]))[:, i]
    return {2: two, 3: three}[n]


def _prior_name(i, n):
    def two(a, b):
        return f"prior{i}"

    def three(a, b, c):
        return f"prior{i}"
    return {2: two, 3: three}[n]


def _score(coef, names, truth, theta_true):
    expected = np.zeros_like(coef)
    for (i, term), c in truth.items():
        expected[i, names.index(term)] = c
    right = bool(np.array_equal(coef != 0, expected != 0))
    g_error = float(np.linalg.norm(theta_true @ (coef - expected).T)
                    / np.linalg.norm(theta_true @ expected.T))
    return right, g_error


def _study(name, system, levels, seeds, methods=METHODS):
    t, x = _truth(system)
    library = dc.PolynomialLibrary(system["degree"]).fit([f"x{i + 1}" for i in range(x.shape[1])])
    names, theta_true = library.get_feature_names(), library.transform(x)
    out = {m: {} for m in methods}
    for level in tqdm(levels, desc=name, disable=None, leave=False):
        scores = {m: [] for m in methods}
        for seed in seeds:
            noisy = x + level * x.std(axis=0) * np.random.default_rng(seed).standard_normal(
                x.shape)
            for method in methods:
                if level == 0 and seed != seeds[0] and method in DETERMINISTIC:
                    scores[method].append(scores[method][0])   # noise-free: the same data
                    continue
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    coef = _ours(method, system, noisy, system["dt"]) if \
                        not method.startswith("PySINDy") else _pysindy(method, system, noisy, t)
                scores[method].append(_score(coef, names, system["truth"], theta_true))
        for method, rows in scores.items():
            out[method][f"{level:g}"] = {
                "right_terms_seeds": int(sum(r for r, _ in rows)), "n_seeds": len(rows),
                "median_relative_error_of_g": float(np.median([e for _, e in rows]))}
    return out


def run(out_dir, *, quick: bool = False) -> Path:
    """The study; ``quick`` (tests): noise 0, 5 and 20 %, 3 seeds, ``QUICK_METHODS``."""
    levels = (0.0, 0.05, 0.2) if quick else LEVELS
    seeds = range(3 if quick else 20)
    methods = QUICK_METHODS if quick else METHODS
    rep = Report(out_dir, "noise-study", title="Noise study: where each way of fitting breaks")
    rep.text(__doc__.split("\n\n", 1)[1].replace("\n", " "))
    if quick:
        rep.text("**Quick run** (tests): 3 noise levels, 3 seeds, " + " and ".join(methods)
                 + " only.")
    rep.results.update({"noise_levels_fraction_of_state_std": list(levels),
                        "n_seeds": len(seeds), "methods": list(methods)})
    for name, system in systems().items():
        study = _study(name, system, levels, seeds, methods)
        rep.results[name] = study
        rep.text(f"### {name}\n\nRight terms (seeds of {len(seeds)}) / median relative error "
                 "of g on the true states:")
        rep.table(["noise", *methods], [[f"{100 * level:g} %", *[_cell(study[m][f"{level:g}"])
                                                                for m in methods]]
                                       for level in levels])
        holds = {m: _holds_up_to(study[m], levels) for m in methods}
        rep.results[name]["all_seeds_right_up_to_noise"] = holds
        rep.text("Highest noise at which every seed has exactly the right terms: " + "; ".join(
            f"{m}: {'none' if v is None else f'{100 * v:g} %'}" for m, v in holds.items())
            + ".")
        rep.figure(_figure(name, study, levels, methods), f"{name.lower().replace(' ', '_')}.png",
                   f"{name}: fraction of seeds with the right terms, and the median error of g")
    return rep.write()


def _holds_up_to(rows, levels):
    """The highest noise level up to which every seed had the right terms (None: not even
    the first)."""
    best = None
    for level in levels:
        row = rows[f"{level:g}"]
        if row["right_terms_seeds"] < row["n_seeds"]:
            break
        best = level
    return best


def _cell(row) -> str:
    return f"{row['right_terms_seeds']} / {100 * row['median_relative_error_of_g']:.2g} %"


def _figure(name, study, levels, methods):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6))
    x = 100 * np.array(levels)
    for method in methods:
        rows = [study[method][f"{level:g}"] for level in levels]
        axes[0].plot(x, [r["right_terms_seeds"] / r["n_seeds"] for r in rows], "o-", ms=4,
                     label=method)
        axes[1].semilogy(x, [max(r["median_relative_error_of_g"], 1e-12) for r in rows],
                         "o-", ms=4, label=method)
    axes[0].set_ylabel("seeds with the right terms")
    axes[1].set_ylabel("median relative error of g")
    for ax in axes:
        ax.set_xlabel("noise (% of each state's standard deviation)")
    axes[0].legend(fontsize=8)
    fig.suptitle(name)
    fig.tight_layout()
    return fig
