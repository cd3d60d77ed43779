"""The double pendulum's energy models shared by the synthetic and the measured experiment:
its friction laws and dissipation model, the rig file's viscous law, and the paper's state form
(``dH`` regressed on state functions) with its report section."""
from __future__ import annotations

import warnings

import numpy as np
import sympy as sp

from discrepancy.differentiation import SavitzkyGolay
from discrepancy.energy import DissipationDiscrepancy, EnergyDiscrepancy, EnergyTautologyWarning
from discrepancy.energy.dissipation import default_friction_library
from discrepancy.symbolic import symbol
from discrepancy.systems.double_pendulum import DoublePendulum


def file_law(params):
    """The rig file's viscous law: ``[(term, k1), (term, k2)]``."""
    terms = friction_library(DoublePendulum())
    return [(terms[0], params.k1), (terms[1], params.k2)]


#: the double pendulum's coordinates (absolute angles, the elbow turns at dphi1 - dphi2)
PHI = DoublePendulum().position_names


def friction_library(pend: DoublePendulum, **kwargs):
    """The default friction laws for the pendulum's joints (``joints()`` of the system)."""
    return default_friction_library([f"d{n}" for n in pend.position_names],
                                    joints=pend.joints(), **kwargs)


def dissipation_model(pend: DoublePendulum, **kwargs) -> DissipationDiscrepancy:
    """A dissipation-form model of ``pend`` with its names and friction laws (unless given)."""
    return DissipationDiscrepancy.from_system(pend, **kwargs)


def state_libraries():
    """The paper's library (cubic polynomials + Fourier up to 3 in all four states, which
    lacks H_m's coupling term) and the same plus ``cos(phi1 - phi2) dphi1 dphi2`` (spans H_m)."""
    import discrepancy as dc

    def paper():
        return dc.PolynomialLibrary(degree=3) + dc.FourierLibrary(n_frequencies=3)

    phi1, phi2, d1, d2 = (symbol(n) for n in ("phi1", "phi2", "dphi1", "dphi2"))
    coupling = dc.CustomLibrary(expressions=[sp.cos(phi1 - phi2) * d1 * d2])
    return {"paper library (does not span H_m)": paper(),
            "paper library + cos(phi1-phi2) dphi1 dphi2 (spans H_m)": paper() + coupling}


def state_form(energy, q_train, t_train, validations, smoothing: dict):
    """Fit the paper's form with both libraries; errors on training and each validation.

    ``smoothing``: the Savitzky-Golay settings (``window_length``, ``polyorder``) of the
    angles' derivatives."""
    import discrepancy as dc

    out = {}
    for name, library in state_libraries().items():
        model = EnergyDiscrepancy(energy, feature_library=library, position_names=PHI,
                                  optimizer=dc.STLSQ(threshold=1e-4, alpha=1e-8),
                                  differentiation_method=SavitzkyGolay(**smoothing))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", EnergyTautologyWarning)
            model.fit(q_train, t_train)
        row = {"span_residual_of_H_m": model.span_residual_,
               "tautology_warning": any(issubclass(w.category, EnergyTautologyWarning)
                                        for w in caught),
               "n_terms": int(np.count_nonzero(model.coef_)),
               "training": model.score(q_train, t_train)}
        for label, (q, t) in validations.items():
            row[label] = model.score(q, t)
        out[name] = row
    return out


def state_form_text(rep, results):
    """The state form's section of a report and its ``results["state_form"]``."""
    rep.text("## Paper's form: dH = E0 - H_m regressed on state functions\n"
             "dH is a path integral of the dissipated power, not a function of the state. "
             "A library that spans H_m fits it as E0 - H_m (training error near 0, no friction "
             "learned) and is wrong on a swing with another initial energy; a library that "
             "does not span H_m cannot represent dH.")
    rows = []
    for name, r in results.items():
        row = [name, r["span_residual_of_H_m"], r["tautology_warning"], r["n_terms"],
               r["training"]["max_abs_percent_of_max"]]
        row += [r[k]["max_abs_percent_of_max"] for k in r if k.startswith("validation")]
        rows.append(row)
    rep.text("Seed 0 (synthetic) or the recording (measured):")
    rep.table(["library", "span residual", "warned", "terms", "train %max", "val %max"], rows)
    rep.results["state_form"] = results
