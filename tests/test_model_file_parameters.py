"""Every constructor parameter of DiscrepancyModel (the one public estimator with a model
file) survives save and load: the same ``get_params`` and the same behaviour, checked
against iterating a map by hand and against refitting a fresh model with the original
parameters."""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from sklearn.base import clone

import discrepancy as dc
from discrepancy.errors import ModelFileError
from discrepancy.models.files.model_parameters import CODECS, STORED_ELSEWHERE
from discrepancy.symbolic import symbol


def test_the_file_declares_exactly_the_constructor_parameters():
    constructor = set(dc.DiscrepancyModel._param_defaults())
    assert set(CODECS) | set(STORED_ELSEWHERE) == constructor
    assert set(dc.DiscrepancyModel._parameter_constraints) == constructor


def _rhs(t, x):
    u = np.sin(2 * t)
    return [x[1], -x[0] - 0.3 * x[1] + 0.5 * u]


T = np.arange(600) * 0.01
X = solve_ivp(_rhs, (0, T[-1]), [1.0, 0.0], t_eval=T, rtol=1e-10, atol=1e-12).y.T
U = np.sin(2 * T)[:, None]


def prior(x, u):
    return np.column_stack([x[:, 1], -x[:, 0]])


FD = "finite_difference"
#: one row per parameter (with several values where the file stores them differently):
#: (id, constructor arguments besides the defaults used, whether get_params comes back equal)
CASES = [
    ("prior callable", dict(prior=prior), True),
    ("prior sympy", dict(prior=[symbol("x2"), -symbol("x1")]), True),
    ("feature_library text", dict(feature_library="poly(1)"), True),
    ("feature_library object", dict(feature_library=dc.PolynomialLibrary(degree=1)), False),
    ("optimizer registered", dict(optimizer=dc.STLSQ(threshold=0.02)), True),
    ("optimizer text", dict(optimizer="lasso(alpha=0.001)"), True),
    ("optimizer sr3", dict(optimizer=dc.SR3()), True),
    ("differentiation_method registered",
     dict(differentiation_method=dc.SavitzkyGolay(window_length=11)), True),
    ("differentiation_method text", dict(differentiation_method="spline"), True),
    ("state_names", dict(state_names=["pos", "vel"]), True),
    ("input_names", dict(input_names="force"), True),
    ("constraints", dict(constraints=dc.Constraints(
        exact_equations=["x1"], at_most=[({("x2", "x2"): 1.0}, -0.25)])), True),
    ("selection", dict(selection="optimizer"), True),
]


def _model(kw):
    base = {"differentiation_method": FD, "optimizer": dc.STLSQ(threshold=0.05),
            "feature_library": "poly(2)"}
    return dc.DiscrepancyModel(**{**base, **kw})


def _same_params(a, b):
    for name in dc.DiscrepancyModel._param_defaults():
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, dc.base.Estimator):
            assert type(x) is type(y) and x.get_params(deep=False) == y.get_params(deep=False), name
        else:
            assert x == y, name


@pytest.mark.parametrize("name, kw, same", CASES, ids=[c[0] for c in CASES])
def test_every_parameter_survives_save_and_load(name, kw, same, tmp_path):
    model = _model(kw).fit(X, T, u=U)
    model.save(tmp_path / "m.json")
    loaded = dc.load_model(tmp_path / "m.json", prior=prior if kw.get("prior") is prior else None)
    if same:
        _same_params(model, loaded)
    np.testing.assert_array_equal(loaded.coef_, model.coef_)
    np.testing.assert_allclose(loaded.simulate(X[0], T[:50], u=U[:50]),
                               model.simulate(X[0], T[:50], u=U[:50]), rtol=1e-12, atol=1e-12)
    # the parameters carry their behaviour: refitting the loaded model's parameters gives
    # the coefficients the original parameters give
    refit, again = clone(loaded).fit(X, T, u=U), clone(model).fit(X, T, u=U)
    np.testing.assert_allclose(refit.coef_, again.coef_, rtol=1e-10, atol=1e-12)


def test_constraints_survive_and_still_bind(tmp_path):
    constraints = dc.Constraints(exact_equations=["x1"], at_most=[({("x2", "x2"): 1.0}, -0.25)])
    model = _model({"constraints": constraints}).fit(X, T, u=U)
    model.save(tmp_path / "m.json")
    loaded = clone(dc.load_model(tmp_path / "m.json")).fit(X, T, u=U)
    names = loaded.get_feature_names()
    assert not np.any(loaded.coef_[0])                       # x1's equation kept exact
    assert loaded.coef_[1, names.index("x2")] <= -0.25 + 1e-9   # the bound honoured


def test_a_discrete_time_map_comes_back_a_map(tmp_path):
    """x[k+1] = 0.9 x[k]: 1, 0.9, 0.81 before and after the file (not 1, 2.46, 6.05)."""
    model = dc.DiscrepancyModel.from_prior([0.9 * symbol("x")], state_names=["x"],
                                           discrete_time=True)
    model.save(tmp_path / "m.json")
    loaded = dc.load_model(tmp_path / "m.json")
    assert loaded.discrete_time is True
    hand = [1.0]
    for _ in range(4):
        hand.append(0.9 * hand[-1])
    np.testing.assert_allclose(loaded.simulate([1.0], 5).ravel(), hand, rtol=1e-15)


def test_a_fitted_map_with_input_comes_back_a_map(tmp_path):
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, (200, 1))
    x = np.zeros((200, 1))
    for k in range(199):
        x[k + 1] = 0.5 * x[k] + 1.0 * u[k]
    model = dc.DiscrepancyModel(feature_library="poly(1)", optimizer=dc.STLSQ(threshold=0.05),
                                discrete_time=True, selection="optimizer").fit(x, u=u)
    model.save(tmp_path / "m.json")
    loaded = dc.load_model(tmp_path / "m.json")
    _same_params(model, loaded)
    np.testing.assert_allclose(loaded.simulate(x[0], 200, u=u)[:, 0], x[:, 0], atol=1e-9)


def test_version_3_files_load_as_continuous_time_with_default_parameters(tmp_path):
    model = _model({}).fit(X, T, u=U)
    doc = model.to_state()
    assert doc["version"] == 4
    doc["version"] = 3
    del doc["parameters"]
    old = dc.DiscrepancyModel.from_state(doc)
    assert old.discrete_time is False and old.constraints is None and old.selection == "auto"
    np.testing.assert_array_equal(old.coef_, model.coef_)


@pytest.mark.parametrize("key, value, pattern", [
    ("discrete_time", "yes", "parameters.discrete_time must be a bool"),
    ("selection", "everything", "selection"),
    ("constraints", {"exact_equations": "x1"}, "parameters.constraints"),
    ("optimizer", {"as": "code", "value": "__import__('os')"}, "parameters.optimizer"),
    ("optimizer", {"as": "spec", "value": {"name": "stlsq", "params": {"threshold": -1}}},
     "parameters.optimizer"),
    ("feature_library", {"as": "text", "value": "poly(x)"}, "parameters"),
])
def test_edited_parameters_are_refused(key, value, pattern, tmp_path):
    doc = _model({}).fit(X, T, u=U).to_state()
    doc["parameters"][key] = value
    (tmp_path / "m.json").write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match=pattern):
        dc.load_model(tmp_path / "m.json")
