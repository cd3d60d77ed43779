"""Energy laws beyond the paper's pendulum: one-, two- and three-link chains, blind and sound.

Recordings come from :mod:`.energy_recordings` (rods written as ``T`` and ``V``, friction of
five families, encoder angles). On each, the library's own blind protocol
(:func:`~discrepancy.energy.blind_fit` of ``DissipationDiscrepancy.from_system(model)``,
nothing else set) chooses a friction law on the first 80 % and is validated once on the
rest. Reported per recording: the validation error (% of the validation window's ``dH``
range) beside that of the true friction law integrated along the same estimated states
(what the measurement allows), whether the law is sound on the whole recording (its torque
at each joint's turning points below the holding torque and below the gravity torque
there; its whole torque below the largest gravity torque), and the CPU time of the blind
fit. The protocol was developed on seed 0 of every family and chain (and seeds 0-5 of the
strong-Stribeck single pendulum); ``--full`` adds the held-out set, seed 100 of every family
and chain, on which nothing was tuned.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid

from discrepancy.energy import DissipationDiscrepancy, blind_fit, error_summary, percent_error

from .energy_recordings import FAMILIES, simulate
from .report import Report

SPLIT = 0.8        # training share of each recording
BAR = 10.0         # % of the validation window's dH range
SHOWN = ((1, "strong Stribeck", 0), (2, "viscous + Coulomb", 1), (3, "viscous + Coulomb", 0))
QUICK = ((1, "viscous + Coulomb", 0),)
#: integration tolerance of quick (test) runs (the experiments' 1e-10 costs a third more
#: CPU): the quick recording's states move by 3e-5 rad/s at most, 31 of its 38 238 encoder
#: readings by a count, its fitted law's coefficients by 3e-5 of themselves
QUICK_TOLERANCE = 1e-8
HELD_OUT = tuple((links, family, 100) for links in (1, 2, 3) for family in FAMILIES)


def evaluate(recording) -> tuple[dict, dict]:
    """The blind protocol on one recording: its summary row and the validation panel."""
    q, t = recording.q, recording.t
    split = int(SPLIT * len(t))
    start = time.process_time()
    blind = blind_fit(DissipationDiscrepancy.from_system(recording.model), q, t, split=split,
                      progress=False)
    seconds = time.process_time() - start
    model = blind.model
    x, times = model.states(q, t)
    k = int(np.searchsorted(times, t[split]))
    dh, pred = model.anchored(x, times)
    true = cumulative_trapezoid(recording.dissipated_power(x), times, initial=0.0)
    true_law = dh[k] + true[k:] - true[k]
    record = model.prepare(x, times)
    check = record.check(len(times), [record.terms.index(term) for term in model.terms_],
                         model.coef_)
    row = {"recording": recording.name, "seconds": float(t[-1]),
           "validation_error_percent": error_summary(dh[k:], pred[k:])[
               "max_abs_percent_of_range"],
           "validation_error_percent_true_law": error_summary(dh[k:], true_law)[
               "max_abs_percent_of_range"],
           "law": model.equation(), "terms": model.identified_terms(),
           "chosen_procedure": blind.chosen, "smoothing": {
               key: blind.smoothing[key] for key in ("window_length", "polyorder")},
           "sound_on_whole_recording": check["sound"],
           "max_static_torque_over_holding_torque_at_turning_points": max(
               [j["largest_static_over_holding_torque"] for j in check["joints"].values()],
               default=0.0),
           "max_whole_law_torque_over_largest_gravity_torque": max(
               [j["largest_torque_over_limit"] for j in check["joints"].values()], default=0.0),
           **_gravity_ratios(recording, model, record),
           "active_constraints": model.soundness_["active_constraints"],
           "blind_fit_seconds": seconds}
    panel = {"t": times[k:], "delta_h": dh[k:], "model": pred[k:], "label": recording.name,
             "error": percent_error(dh[k:], pred[k:], normaliser="range"),
             "error_label": "error (% of the window's dH range)"}
    return row, panel


def _gravity_ratios(recording, model, record) -> dict:
    """The law's torque at each joint's turning points (where its exact speed changes sign)
    over the gravity torque of that joint there (``|dV/dq_i|``), largest over joints; and
    the same for the true friction's break-away torque."""
    x = recording.x
    k = x.shape[1] // 2
    gravity = np.abs(recording.model.conservative_torques(x))
    law, truth = 0.0, 0.0
    for i, axis in enumerate(record.axes[:k]):
        speed = x[:, k + i]
        turns = np.flatnonzero(np.sign(speed[1:]) != np.sign(speed[:-1]))
        turns = turns[(recording.t[turns] >= record.t[0]) & (recording.t[turns] <= record.t[-1])]
        if not len(turns):
            continue
        used = [(record.terms.index(term), c) for term, c in zip(model.terms_, model.coef_,
                                                                 strict=True)
                if record.terms.index(term) in axis.terms]
        nearest = np.clip(np.searchsorted(record.t, recording.t[turns]), 0, len(record.t) - 1)
        torque = sum(c * record.torques[nearest, j] for j, c in used) if used else 0.0
        law = max(law, float(np.max(torque / gravity[turns, i])))
        truth = max(truth, float(np.max(recording.static_friction()[i] / gravity[turns, i])))
    return {"max_static_torque_over_gravity_torque_at_turning_points": law,
            "true_static_friction_over_gravity_torque_at_turning_points": truth}


def run(out_dir, *, quick: bool = False, full: bool = False) -> Path:
    """Blind fits on the shown recordings (one of each chain; ``quick``: a single pendulum,
    simulated at ``QUICK_TOLERANCE``), with ``full`` also the held-out set."""
    rep = Report(out_dir, "energy-systems", title="Energy laws on simulated one-, two- and "
                 "three-link chains: blind, sound, timed")
    sets = {"default_recordings": QUICK if quick else SHOWN,
            **({"held_out_recordings": HELD_OUT} if full else {})}
    panels = []
    for label, keys in sets.items():
        rows = []
        for key in keys:
            row, panel = evaluate(simulate(*key, tolerance=QUICK_TOLERANCE) if quick
                                  else simulate(*key))
            rows.append(row)
            panels.append(panel)
        rep.results[label] = {"recordings": rows, "summary": _summary(rows)}
    three = [r for r in rep.results["default_recordings"]["recordings"]
             if r["recording"].startswith("3")]
    if three:
        rep.results["three_link_blind_fit_seconds"] = three[0]["blind_fit_seconds"]
    _report(rep, panels)
    return rep.write()


def _summary(rows) -> dict:
    errors = np.array([r["validation_error_percent"] for r in rows])
    return {"recordings": len(rows),
            "within_bar": int(np.sum(errors <= BAR)), "bar_percent_of_range": BAR,
            "sound_on_whole_recording": int(sum(r["sound_on_whole_recording"] for r in rows)),
            "static_torque_below_gravity_torque_at_every_turning_point": int(sum(
                r["max_static_torque_over_gravity_torque_at_turning_points"] < 1 for r in rows)),
            "median_validation_error_percent": float(np.median(errors)),
            "median_validation_error_percent_true_law": float(np.median(
                [r["validation_error_percent_true_law"] for r in rows])),
            "largest_blind_fit_seconds": float(max(r["blind_fit_seconds"] for r in rows))}


def _report(rep, panels):
    from ..plots.energy import fit_figure, soundness_figure

    rep.text("Each recording is fitted by `blind_fit(DissipationDiscrepancy.from_system(model), "
             "q, t, split=0.8 m)` and nothing else: the smoothing, the library (viscous, "
             "Coulomb, Stribeck at 0.1, 0.3 and 1 rad/s, air drag per joint), the fit window, "
             "block or cumulative fit and the term selection are chosen inside the first 80 %. "
             "'true law' is the simulated friction integrated along the same estimated states: "
             "the error the measurement itself leaves. 'static / gravity' is the law's largest "
             "torque at a joint's turning points over the gravity torque of that joint there; "
             "'static / holding' the same over the torque that holds the joint at rest while "
             "the other links move (the constraint of the fit, equal to the gravity torque for "
             "one link). CPU seconds by `time.process_time`.")
    for label, block in rep.results.items():
        if not isinstance(block, dict) or "recordings" not in block:
            continue
        rep.text(f"## {label.replace('_', ' ')}")
        rep.table(["recording", "validation % range", "true law % range", "sound",
                   "static / gravity", "static / holding", "CPU s", "law"],
                  [[r["recording"], r["validation_error_percent"],
                    r["validation_error_percent_true_law"], r["sound_on_whole_recording"],
                    r["max_static_torque_over_gravity_torque_at_turning_points"],
                    r["max_static_torque_over_holding_torque_at_turning_points"],
                    r["blind_fit_seconds"], r["law"]] for r in block["recordings"]])
        s = block["summary"]
        rep.text(f"{s['within_bar']}/{s['recordings']} within {BAR:g} % of the window's "
                 f"range, {s['sound_on_whole_recording']}/{s['recordings']} sound on the whole "
                 "recording; median error "
                 f"{s['median_validation_error_percent']:.3g} % (true law "
                 f"{s['median_validation_error_percent_true_law']:.3g} %).")
        rep.figure(soundness_figure(block["recordings"], bar=BAR), f"{label}_summary.png",
                   "Validation error of the blind law and of the true law; static torque "
                   "at the turning points over the gravity torque there")
    rep.figure(fit_figure(panels[:3], title="blind laws over the validation part"),
               "blind_validation.png", "The blindly chosen laws over the validation part")
