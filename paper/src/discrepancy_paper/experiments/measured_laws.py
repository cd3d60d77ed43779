"""The measured swing's laws: the library's own blind fit and what each law amounts to
(training fit continued through validation, energy and torque per term)."""
from __future__ import annotations

import numpy as np

from discrepancy.energy import BlindFit, blind_fit, error_summary
from discrepancy.energy.dissipation import integrated_powers
from discrepancy.symbolic import compile_numpy
from discrepancy.systems.double_pendulum import DoublePendulum

from .pendulum_forms import dissipation_model


def library_blind(pend: DoublePendulum, rec, n_origins: int) -> BlindFit:
    """The library's own blind procedure, nothing set for this recording: the model of the
    rig (energy, names, joints) and ``blind_fit``'s defaults (smoothing chosen on the
    training part, default libraries, windows, fits and selections, sound laws only)."""
    return blind_fit(dissipation_model(pend), rec.angles, rec.t, split=rec.split_index,
                     n_origins=n_origins, progress=False)


def library_summary(blind: BlindFit, rec) -> tuple[dict, dict]:
    """Law, validation error (continued) and soundness, checked on the training part (the
    fit's constraints) and, after the fact, on the whole recording; and the curves
    ``{"t", "delta_h", "model", "split"}`` for the figure."""
    model = blind.model
    x, t = model.states(rec.angles, rec.t)
    split = int(np.searchsorted(t, rec.split_time))
    dh, pred, errors = continued_errors(model, x, t, split)
    record = model.prepare(x, t)
    whole = record.check(len(t), [record.terms.index(term) for term in model.terms_],
                         model.coef_)
    curves = {"t": t, "delta_h": dh, "model": pred, "split": split}
    return {"chosen_procedure": blind.chosen, "smoothing": blind.smoothing,
            "equation": model.equation(), "identified_terms": model.identified_terms(),
            "terms": term_magnitudes(model, x[:split], t[:split]),
            "training_internal_forecast_errors_percent_of_range":
                blind.procedures[blind.chosen]["forecast_errors_percent_of_range"],
            "validation_continued_percent_of_range":
                errors["validation_continued"]["max_abs_percent_of_range"],
            "training": errors["training"],
            "soundness_on_training": blind.soundness,
            "soundness_on_whole_recording": whole,
            "procedures": {name: {**row, "validation_continued_percent_of_range":
                                  continued_errors(blind.models[name], x, t, split)[2][
                                      "validation_continued"]["max_abs_percent_of_range"]}
                           for name, row in blind.procedures.items()}}, curves


def fit_start_index(model, t) -> int:
    """Index of the first sample the model was fitted on (0 unless it has a fit window)."""
    return int(np.argmin(np.abs(t - model.fit_start_)))   # as model.anchored places it


def continued_errors(model, x, t, split):
    """Errors of the model integrated from where its fitted data begin through the recording
    (training fit continued), on its training data and on validation; and restarted at the
    measured dH where validation begins."""
    dh, pred = model.anchored(x, t)
    k0 = fit_start_index(model, t)
    anchored = pred[split:] - pred[split] + dh[split]
    return dh, pred, {"training": error_summary(dh[k0:split], pred[k0:split]),
                      "validation_continued": error_summary(dh[split:], pred[split:]),
                      "validation_restarted_at_window_start": error_summary(dh[split:], anchored)}


def term_magnitudes(model, x, t) -> list[dict]:
    """Every learned term's physical size over states ``x`` at times ``t``: coefficient, the
    energy it dissipates (J) and its share, and for joint laws the mean torque it exerts
    while its joint moves (N m) and that torque over the largest conservative torque."""
    lost = energy_lost_per_term(model, x, t)
    total = sum(lost.values())
    rows = []
    for term, c in zip(model.terms_, model.coef_, strict=True):
        row = {"name": term.name, "coefficient": float(c), "unit": term.unit,
               "energy_lost_J": lost[term.name], "share_percent": 100 * lost[term.name] / total}
        if term.speed is not None:
            w = np.abs(compile_numpy(term.speed, model.variable_names_)(x))
            row["mean_torque_N_m"] = lost[term.name] / float(np.trapezoid(w, t))
            row["mean_torque_over_largest_conservative"] = row["mean_torque_N_m"] / \
                model.torque_limit_
        rows.append(row)
    return rows


def energy_lost_per_term(model, x, t) -> dict[str, float]:
    """Energy (J) each learned term dissipates along states ``x`` at times ``t``."""
    lost = integrated_powers(model.terms_, x, t, model.variable_names_)[-1] * model.coef_
    return dict(zip((term.name for term in model.terms_), lost.tolist(), strict=True))


def equivalent_viscous(model, x, t) -> dict[str, float]:
    """Per joint, the viscous coefficient (N m s) dissipating what the learned laws of that
    joint dissipate over the recording: ``int P_joint dt / int w^2 dt``."""
    speeds = {"joint 1": x[:, 2], "joint 2": x[:, 2] - x[:, 3]}
    lost = energy_lost_per_term(model, x, t)
    return {joint: sum(e for name, e in lost.items() if name.split(" (")[0].endswith(joint))
            / float(np.trapezoid(w ** 2, t)) for joint, w in speeds.items()}
