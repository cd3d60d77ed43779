"""The blind protocol: procedures chosen from training data alone, frozen, validated once."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.energy import blind_fit, default_procedures
from discrepancy.errors import DataError, ParameterError

M, L, G, K, F = 0.5, 0.4, 9.81, 2e-3, 4e-3


@pytest.fixture(scope="module")
def swing():
    """A rod pendulum (T, V written by hand) with viscous and smoothed Coulomb friction,
    24 s at 1 kHz read by a 5000-count encoder; validation is the last 20 %."""
    q, w = sp.symbols("q dq")
    inertia = M * L ** 2 / 3
    system = dc.systems.LagrangianSystem(
        inertia * w ** 2 / 2, -M * G * L / 2 * sp.cos(q), ["q"],
        dissipation=K * w ** 2 / 2 + F * sp.sqrt(w ** 2 + 1e-6))
    t = np.arange(24001) / 1000
    x = system.simulate([2.6, 0.0], t, rtol=1e-11, atol=1e-11)
    step = 2 * np.pi / 5000
    angles = np.round(x[:, :1] / step) * step
    return system, angles, t, int(0.8 * len(t))


@pytest.fixture(scope="module")
def blind(swing):
    system, q, t, split = swing
    return blind_fit(dc.DissipationDiscrepancy(system.energy), q, t, split=split,
                     progress=False)


def test_chooses_the_true_law_from_training_alone(swing, blind):
    laws = {term.name: c for term, c in zip(blind.model.terms_, blind.model.coef_, strict=True)}
    assert set(laws) == {"viscous joint 1", "Coulomb joint 1"}
    assert laws["viscous joint 1"] == pytest.approx(K, rel=0.02)
    assert laws["Coulomb joint 1"] == pytest.approx(F, rel=0.02)
    _, _, t, split = swing
    assert all(o + blind.horizon <= t[split - 1] + 1e-9 for o in blind.origins)
    assert len(blind.procedures) == 24   # 2 libraries x 3 windows x 2 fits x 2 selections


def test_nothing_after_the_split_is_read(swing, blind):
    """Replacing the validation part by other data changes nothing."""
    system, q, t, split = swing
    other = q.copy()
    other[split:] = np.random.default_rng(1).uniform(-3, 3, size=other[split:].shape)
    again = blind_fit(dc.DissipationDiscrepancy(system.energy), other, t, split=split,
                      progress=False)
    assert again.chosen == blind.chosen
    np.testing.assert_array_equal(again.model.coef_, blind.model.coef_)
    assert again.procedures == blind.procedures


def test_form_error_band_holds_the_validation_window(swing, blind):
    """The band from the rolling-origin forecasts (nominal 2/3 with 5 origins) holds most
    of the measured dH over validation, which the law continues from training."""
    system, q, t, split = swing
    model = blind.model
    x, times = model.states(q, t)
    k = int(np.searchsorted(times, t[split]))
    dh, pred = model.anchored(x, times)
    low, high = blind.forecast_band(pred[k:], times[k:])
    inside = np.mean((low <= dh[k:]) & (dh[k:] <= high))
    assert inside >= 0.6
    assert np.all(high - low > 0)


def test_restricted_choice_and_bad_arguments(swing, blind):
    system, q, t, split = swing
    names = [n for n in blind.procedures if "no Stribeck" in n]
    sub = blind.restricted(names)
    best = min(blind.procedures[n]["forecast_worst_percent_of_range"] for n in names)
    assert set(sub.procedures) == set(names)
    assert blind.procedures[sub.chosen]["forecast_worst_percent_of_range"] <= best * 1.02
    with pytest.raises(ParameterError, match="unknown"):
        blind.restricted(["no such procedure"])
    model = dc.DissipationDiscrepancy(system.energy)
    with pytest.raises(ParameterError, match="split"):
        blind_fit(model, q, t, split=len(t))
    with pytest.raises(ParameterError, match="n_origins"):
        blind_fit(model, q, t, split=split, n_origins=1)
    with pytest.raises(ParameterError, match="candidates"):
        blind_fit({"a": 1}, q, t, split=split)
    with pytest.raises(ParameterError, match="horizon"):
        blind_fit(model, q, t, split=split, horizon=-1.0)
    with pytest.raises(DataError, match="too short"):
        blind_fit(model, q, t, split=split, horizon=15.0)


def test_default_procedures_vary_fit_selection_and_library(swing):
    system, *_ = swing
    procedures = default_procedures(dc.DissipationDiscrepancy(system.energy), 32.0, 1)
    params = [p.get_params(deep=False) for p in procedures.values()]
    assert {p["block_seconds"] for p in params} == {None, 1.0}
    assert {p["holdout"] for p in params} == {0.0, 0.2}
    windows = sorted({p["fit_window"] or 0.0 for p in params})
    assert windows == pytest.approx([0.0, 9.6, 16.0])    # all data, last 30 % and 50 %
    sizes = {len(p["friction_terms"]) for p in params}
    assert sizes == {6, 3}      # viscous, Coulomb, air drag (+ Stribeck at 3 speeds)


def test_fit_window_fits_the_last_seconds_and_anchors_there(swing):
    """A fit on the last 8 s recovers the true friction from those seconds alone (a fit on
    the first 8 s of the same swing would see 3 times the speeds); anchored() puts model and
    dH at the window's start, where the law's prediction begins."""
    system, q, t, _ = swing
    windowed = dc.DissipationDiscrepancy(system.energy, fit_window=8.0).fit(q, t)
    laws = dict(zip([term.name for term in windowed.terms_], windowed.coef_, strict=True))
    assert laws["viscous joint 1"] == pytest.approx(K, rel=0.05)
    assert laws["Coulomb joint 1"] == pytest.approx(F, rel=0.05)
    x, times = windowed.states(q, t)
    assert windowed.fit_start_ == pytest.approx(times[-1] - 8.0, abs=1e-3)
    dh, model = windowed.anchored(x, times)
    k = int(np.argmin(np.abs(times - windowed.fit_start_)))
    assert dh[k] == 0 and model[k] == pytest.approx(windowed.offset_)
    assert np.sqrt(np.mean((dh[k:] - model[k:]) ** 2)) < 0.01 * np.ptp(dh[k:])


def test_origin_fits_share_the_recording_but_read_nothing_after_their_origin(swing):
    """A procedure fitted from the shared prepared training part up to an origin equals the
    same procedure fitted on the positions before that origin alone."""
    system, q, t, split = swing
    model = dc.DissipationDiscrepancy(system.energy, block_seconds=1.0, holdout=0.2)
    record = model.prepare(*model.states(q[:split], t[:split]))
    edge = 15                                  # the default smoother's half window
    shared = dc.DissipationDiscrepancy(**model.get_params()).fit_prepared(record,
                                                                          12000 - 2 * edge)
    alone = dc.DissipationDiscrepancy(**model.get_params()).fit(q[:12000], t[:12000])
    assert [term.name for term in shared.terms_] == [term.name for term in alone.terms_]
    np.testing.assert_allclose(shared.coef_, alone.coef_, rtol=1e-9)
    assert shared.offset_ == pytest.approx(alone.offset_, rel=1e-9)


def test_from_system_takes_names_and_relative_joints_from_the_system():
    """A double pendulum in absolute angles: the elbow turns at dphi1 - dphi2, and the names
    are the system's, not q1, q2."""
    pend = dc.systems.DoublePendulum()
    model = dc.DissipationDiscrepancy.from_system(pend, max_terms=2)
    names = [term.name for term in model.friction_terms]
    assert "viscous joint 2" in names and model.position_names == ["phi1", "phi2"]
    elbow = next(term for term in model.friction_terms if term.name == "viscous joint 2")
    phi = sp.symbols("dphi1 dphi2")
    assert sp.simplify(elbow.power.subs(dict(zip(sorted(elbow.power.free_symbols, key=str),
                                                 phi, strict=True))) - (phi[0] - phi[1]) ** 2) == 0
    assert model.max_terms == 2
    with pytest.raises(ParameterError, match="joints"):
        dc.DissipationDiscrepancy.from_system(dc.systems.VanDerPol())


def test_blind_fit_never_returns_an_unsound_law():
    """A heavily damped rod (viscous friction only): Coulomb friction alone can only carry its
    loss with a break-away above the gravity torque at the late turning points, which would
    have stopped the rod at turning points it swung through, so the constrained procedure
    is chosen. Its energy decays as exp(-c t / I): it is within 0.1 % of rest from
    ln(1000) I / c = 3.7 s, where the forecasts end; the turning points after it still bound
    the law."""
    q, w = sp.symbols("q dq")
    rod = dc.systems.LagrangianSystem(M * L ** 2 / 6 * w ** 2, -M * G * L / 2 * sp.cos(q),
                                      ["q"], dissipation=0.05 * w ** 2 / 2)
    t = np.arange(15001) / 1000
    x = rod.simulate([2.0, 0.0], t, rtol=1e-11, atol=1e-11)
    coulomb = [term for term in dc.energy.default_friction_library(["dq1"])
               if term.name.startswith("Coulomb")]
    candidates = {
        "Coulomb, unconstrained": dc.DissipationDiscrepancy(
            rod.energy, friction_terms=coulomb, torque_limit=None, turning_points=False),
        "Coulomb, sound": dc.DissipationDiscrepancy(rod.energy, friction_terms=coulomb)}
    with pytest.warns(dc.errors.SelectionWarning, match="at rest from"):
        blind = blind_fit(candidates, x[:, :1], t, split=12000, dq=x[:, 1:], progress=False)
    assert blind.rest_from == pytest.approx(np.log(1000) * M * L ** 2 / 3 / 0.05, abs=0.2)
    assert all(o + blind.horizon <= blind.rest_from + 1e-9 for o in blind.origins)
    free, sound = (blind.procedures[n] for n in candidates)
    assert not free["sound"] and sound["sound"]
    assert blind.chosen == "Coulomb, sound" and blind.soundness["sound"]
    assert any("turning points" in kind for kind in sound["active_constraints"])
    # the sound law's break-away is below m g l/2 |sin q| at every turning point in training
    # where the rod still swings by more than 0.05 rad
    turns = np.flatnonzero(np.sign(x[1:12000, 1]) != np.sign(x[:11999, 1]))
    turns = turns[np.abs(x[turns, 0]) > 0.05]
    lowest = M * G * L / 2 * np.min(np.abs(np.sin(x[turns, 0])))
    assert blind.model.coef_[0] < lowest
    with pytest.raises(dc.errors.ConvergenceError, match="no candidate procedure"), \
            pytest.warns(dc.errors.SelectionWarning):
        blind_fit({"free": candidates["Coulomb, unconstrained"]}, x[:, :1], t, split=12000,
                  dq=x[:, 1:], progress=False)


def test_a_pendulum_that_comes_to_rest_is_judged_where_it_moves():
    """Coulomb friction holds a rod from about 8.6 s of a 20 s training part. Forecasts from
    the part at rest score noise against a range of noise, and a fit on the last 30 % of
    training there finds no loss: the law chosen so was 5 times too small. The forecasts and
    fits now end where it comes to rest, and the law is the true one."""
    q, w = sp.symbols("q dq")
    rod = dc.systems.LagrangianSystem(M * L ** 2 / 6 * w ** 2, -M * G * L / 2 * sp.cos(q),
                                      ["q"], dissipation=K * w ** 2 / 2
                                      + 0.05 * sp.sqrt(w ** 2 + 1e-6))
    t = np.arange(30001) / 1000
    x = rod.simulate([2.6, 0.0], t, rtol=1e-10, atol=1e-10)
    step = 2 * np.pi / 5000
    with pytest.warns(dc.errors.SelectionWarning, match="at rest from"):
        blind = blind_fit(dc.DissipationDiscrepancy(rod.energy), np.round(x[:, :1] / step)
                          * step, t, split=20000, progress=False)
    stops = t[np.flatnonzero(np.abs(x[:, 1]) > 1e-3)[-1]]
    assert stops - 0.5 < blind.rest_from <= stops
    laws = {term.name: c for term, c in zip(blind.model.terms_, blind.model.coef_, strict=True)}
    assert laws["Coulomb joint 1"] == pytest.approx(0.05, rel=0.02)
    assert laws["viscous joint 1"] == pytest.approx(K, rel=0.05)
    assert blind.soundness["sound"]
