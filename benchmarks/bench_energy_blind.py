"""CPU time of the blind energy fit (``discrepancy.energy.blind_fit``) on a three-link
recording: the implementation it replaced (kept below as the reference: every one of the 24
default procedures refitted from the raw angles at each of 5 origins and at the end, each
fit searching all 793 subsets of up to 4 of the 12 terms with a bounded least-squares solve
on all samples) against ours (the training part differentiated and prepared once, each fit
reduced to its Gram statistics, constrained supports from forward and backward stepwise
paths), both measured in this run with ``time.process_time``.

Run: .venv/bin/python benchmarks/bench_energy_blind.py
"""
from __future__ import annotations

import time
from itertools import combinations

import numpy as np
from _common import machine, table
from scipy.ndimage import uniform_filter1d
from scipy.optimize import lsq_linear, nnls

from discrepancy.differentiation import SavitzkyGolay
from discrepancy.energy import DissipationDiscrepancy, blind_fit, default_friction_library
from discrepancy.energy.dissipation import integrated_powers
from discrepancy.energy.protocol import _origins, default_procedures
from discrepancy.energy.record import conservative_torques
from discrepancy.symbolic import compile_numpy
from discrepancy_paper.experiments.energy_recordings import simulate

OLD_LIBRARY = {"stribeck_speed": 0.1}     # the library of the replaced code: 12 terms


# ---- the replaced implementation (reference) -------------------------------------------
def _old_fit(features, target, block, upper):
    k = features.shape[1]
    if block is not None:
        n = len(target) // block
        means = lambda v: v[:n * block].reshape(n, block, *v.shape[1:]).mean(axis=1)  # noqa: E731
        loss, gained = np.diff(means(target)), np.diff(means(features), axis=0)
        w = 1.0 / np.maximum(np.abs(loss), 1e-3 * np.max(np.abs(loss)))
        scale = np.maximum(np.max(np.abs(gained), axis=0), 1e-300)
        xi = lsq_linear(gained * w[:, None] / scale, loss * w, bounds=(0.0, upper * scale),
                        method="bvls").x if np.isfinite(upper).any() else \
            nnls(gained * w[:, None] / scale, loss * w)[0]
        xi = xi / scale
        return np.r_[np.mean(target - features @ xi), xi]
    design = np.column_stack([np.ones(len(target)), features])
    scale = np.maximum(np.max(np.abs(design), axis=0), 1e-300)
    return lsq_linear(design / scale, target, bounds=([-np.inf] + [0.0] * k,
                                                       np.r_[np.inf, upper * scale[1:]]),
                      method="bvls").x / scale


def _old_select(features, target, max_terms, holdout, block, upper, tolerance=0.02):
    m, p = features.shape
    cut, smooth, best = int(round(m * (1 - holdout))), max(1, m // 100), {}
    for k in range(1, max_terms + 1):
        for subset in combinations(range(p), k):
            cols = features[:, subset]
            coef = _old_fit(cols[:cut], target[:cut], block, upper[list(subset)])
            if np.any(coef[1:] == 0):
                continue
            error = target - coef[0] - cols @ coef[1:]
            score = np.max(np.abs(error[cut:])) / np.ptp(target[cut:]) if holdout else \
                np.sqrt(np.mean(uniform_filter1d(error, smooth) ** 2))
            if score < best.get(k, (np.inf,))[0]:
                best[k] = (score, subset)
    sizes = sorted(best)
    chosen = sizes[0] if sizes else None
    for k in sizes[1:]:
        if best[k][0] < best[chosen][0] * (1 - tolerance):
            chosen = k
        else:
            break
    return best[chosen][1] if chosen else ()


def _old_model_fit(model, q, t):
    """One procedure on raw angles: window, differentiate, features, per-term bounds, exhaustive
    search, refit (the replaced ``DissipationDiscrepancy.fit``)."""
    if model.fit_window is not None:
        keep = t >= t[-1] - model.fit_window
        q, t = q[keep], t[keep]
    x, t = model.states(q, t)
    names = model.variable_names(q.shape[1])
    terms = model.friction_terms
    features = integrated_powers(terms, x, t, names)
    target = model.measured_delta_h(x)
    limit = float(np.max(np.abs(conservative_torques(model._energy, x, max_rows=5000))))
    upper = np.full(len(terms), np.inf)
    for j, term in enumerate(terms):
        power = compile_numpy(term.power, names)(x)
        speed = np.abs(compile_numpy(term.speed, names)(x))
        moving = speed > 1e-6 * speed.max()
        upper[j] = limit / np.max(power[moving] / speed[moving])
    block = None if model.block_seconds is None else \
        max(2, int(round(model.block_seconds / np.median(np.diff(t)))))
    support = _old_select(features, target, model.max_terms, model.holdout, block, upper)
    coef = _old_fit(features[:, support], target, block, upper[list(support)])
    return support, coef, t[0]


def old_blind_fit(model, q, t, split, n_origins=5):
    """Median forecast error of every default procedure from 5 origins, then the choice."""
    validation = float(t[-1] - t[split])
    q, t = q[:split], t[:split]
    horizon = min(validation, (t[-1] - t[0]) / 3)
    procedures = default_procedures(model, float(t[-1] - t[0]), q.shape[1])
    medians = {}
    for name, procedure in procedures.items():
        errors = []
        for start in _origins(t, len(t) - 1, horizon, n_origins):
            stop = int(np.searchsorted(t, t[start] + horizon, side="right"))
            support, coef, t0 = _old_model_fit(procedure, q[:start], t[:start])
            x, times = procedure.states(q[:stop], t[:stop])
            k0, k = np.searchsorted(times, t0), np.searchsorted(times, t[start])
            dh = procedure.measured_delta_h(x) - procedure.measured_delta_h(x)[k0]
            features = integrated_powers([procedure.friction_terms[i] for i in support], x,
                                         times, procedure.variable_names(q.shape[1]))
            pred = coef[0] + (features - features[k0]) @ coef[1:]
            errors.append(np.max(np.abs(dh[k:] - pred[k:])) / np.ptp(dh[k:]) * 100)
        _old_model_fit(procedure, q, t)                   # the final fit of the procedure
        medians[name] = float(np.median(errors))
    return min(medians, key=medians.get)


# ---- the run ----------------------------------------------------------------------------
RECORDING = (3, "viscous + Coulomb", 0)    # energy-systems' three-link recording


def cpu(function):
    start = time.process_time()
    out = function()
    return time.process_time() - start, out


def main() -> None:
    recording = simulate(*RECORDING)
    system, q, t = recording.model, recording.q, recording.t
    split = int(0.8 * len(t))
    names = [f"d{n}" for n in system.position_names]
    old_terms = list(default_friction_library(names, joints=system.joints(), **OLD_LIBRARY))
    smoother = SavitzkyGolay(window_length=31, polyorder=3)
    old_model = DissipationDiscrepancy(system.energy, friction_terms=old_terms,
                                       differentiation_method=smoother)
    runs = {
        "replaced implementation (reference)": lambda: old_blind_fit(old_model, q, t, split),
        "ours, same library and smoothing": lambda: blind_fit(old_model, q, t, split=split,
                                                              progress=False).chosen,
        "ours, defaults (21 terms, smoothing chosen)": lambda: blind_fit(
            DissipationDiscrepancy.from_system(system), q, t, split=split,
            progress=False).chosen}
    rows, reference = [], None
    for name, run in runs.items():
        seconds_cpu, chosen = cpu(run)
        reference = reference or seconds_cpu
        rows.append([name, f"{seconds_cpu:.1f}", f"{reference / seconds_cpu:.1f}x", chosen])
    print(machine())
    rate = 1 / np.median(np.diff(t))
    print(f"{recording.name} (energy-systems): {t[-1]:.1f} s at {rate:.0f} Hz, training "
          f"{t[split]:.1f} s; 24 procedures x (5 origins + final fit)")
    print(table(["blind energy fit", "CPU s", "speed-up", "chosen procedure"], rows))


if __name__ == "__main__":
    main()
