"""Pieces shared by the system-identification benchmarks' reports."""
from __future__ import annotations

import numpy as np


def published_table(rep, record: str, ours: float, unit: str, published: dict) -> None:
    """Our figure on ``record`` beside published ones (as reported by their authors)."""
    rows = [["this model (discrepancy)", f"{ours:.3f}"]]
    rows += [[name, f"{value:.3g}"] for name, value in
             sorted(published.items(), key=lambda item: item[1])]
    rep.text(f"Beside published results on the same record ({record}; figures as their "
             "authors report them, not rerun here):")
    rep.table(["model", f"RMS simulation error ({unit})"], rows)


def support_path_figure(path):
    """Held-out forecast error (RMS, scaled) against the number of terms on the path, with
    one standard error, the chosen support marked."""
    import matplotlib.pyplot as plt

    from discrepancy.models.outputs.output_fit import choose

    terms = np.array([s.n_terms for s in path])
    error = np.array([s.heldout_error for s in path])
    spread = np.array([s.heldout_se for s in path]) / (2 * np.maximum(error, 1e-300))
    chosen = choose(path, None)
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.errorbar(terms, error, yerr=spread, fmt="o-", ms=4, capsize=2)
    ax.plot([chosen.n_terms], [chosen.heldout_error], "r*", ms=14, label="chosen")
    ax.set_yscale("log")
    ax.set_xlabel("number of terms")
    ax.set_ylabel("held-out forecast error (scaled RMS)")
    ax.legend()
    return fig


#: the default candidates a quick (test) blind run scores: the linear terms alone or with
#: one family of nonlinear terms; a reproduction scores every default candidate
SMALL_CANDIDATES = "linear"


def blind_candidates(model, y, t, u, *, outputs, fit_kws=None, full: bool) -> dict:
    """The library's default candidates (:func:`discrepancy.selection.default_libraries`)
    for ``model``'s prior and the outputs ``y`` (one record; the states no output measures
    along the prior's simulation, as ``choose_procedure`` places them); unless ``full``
    (quick runs), only the linear terms alone or with one family of nonlinear terms (a rule
    on the candidates' names, fixed before any data were seen)."""
    from discrepancy.models.outputs.output_checks import prior_states
    from discrepancy.selection import default_libraries

    states = prior_states(model, y, t, u, outputs=outputs, **(fit_kws or {}))
    libraries = default_libraries(model.state_names, model.input_names, states,
                                  None if u is None else np.reshape(u, (len(y), -1)),
                                  prior=model.prior)
    return {name: lib for name, lib in libraries.items()
            if full or name.startswith(SMALL_CANDIDATES)}


def blind_results(choice, test_error: float, unit: str, cpu_seconds: float,
                  wall_seconds: float, full: bool) -> dict:
    """``results.json``'s ``blind_procedure`` entry of a :class:`ProcedureChoice`."""
    return {f"test_rms_error_{unit}": test_error,
            "number_of_terms": int(choice.model.complexity),
            "chosen_candidate": choice.chosen,
            "chosen_model_fitted_by": choice.final_route,
            "candidate_scores": {name: {"mean_forecast_error": row["mean"],
                                        "standard_error": row["se"],
                                        "forecast_error_per_origin": row["forecast_errors"],
                                        "number_of_terms": row["n_terms"]}
                                 for name, row in choice.scores.items()},
            "forecast_error_is": "mean squared output error scaled by the output's standard "
                                 "deviation, after each origin to the record's end",
            "origins_as_share_of_record": choice.origins,
            "equations": choice.model.equations(precision=6),
            "fit_seconds": wall_seconds, "fit_cpu_seconds": cpu_seconds,
            "full_candidate_set": full}


def blind_text(rep, choice, test_error: float, unit: str, cpu_seconds: float,
               full: bool) -> None:
    """The blind section's table of candidates and its summary."""
    subset = "every default candidate" if full else (
        "the default candidates that are the linear terms alone or with one family of "
        "nonlinear terms (a quick run)")
    rep.text(f"`discrepancy.choose_procedure` on the estimation record alone, with {subset} "
             "and the prior alone, then the union of the two libraries that forecast best "
             "and, where the benchmark does not fix how the input moves between samples, the "
             "best candidate with each other input hold; each scored by rolling-origin output "
             "forecasts inside the estimation record, the winner's whole procedure run again "
             "on all of it (or its scored fit refined on all of it, when that fits the "
             "estimation record better with no more terms). Nothing here was chosen after "
             "seeing test data.")
    rep.text(f"**Test RMS error: {test_error:.3f} {unit}**, {choice.model.complexity} "
             f"discrepancy terms, chosen candidate: **{choice.chosen}**, fitted by "
             f"{choice.final_route}; {cpu_seconds:.0f} CPU seconds.")
    rep.table(["candidate", "terms (fitted on the largest part)", "forecast error (scaled MSE)",
               "± s.e.", ""],
              [[name, row["n_terms"], f"{row['mean']:.4g}", f"{row['se']:.2g}",
                "chosen" if name == choice.chosen else ""]
               for name, row in choice.scores.items()])
    rep.text("```\n" + "\n".join(f"({s})' = {e}" for s, e in zip(
        choice.model.state_names_, choice.model.equations(precision=5), strict=True)) + "\n```")
