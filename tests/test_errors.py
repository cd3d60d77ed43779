"""Bad input: the right discrepancy.errors subclass, with a message naming the argument."""
from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy import errors
from discrepancy.errors import (
    DataError,
    DiscrepancyError,
    ModelFileError,
    NotFittedError,
    ParameterError,
    PriorError,
    ShapeError,
    UnknownNameError,
)
from discrepancy.symbolic import symbol


def vdp(x, u=None):
    return np.column_stack([x[:, 1], 0.5 * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]])


def data(m=200, seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(m, 2)), rng.normal(size=(m, 1))


def model(**kw):
    kw.setdefault("feature_library", dc.PolynomialLibrary(degree=2))
    kw.setdefault("optimizer", dc.STLSQ(threshold=0.05))
    return dc.DiscrepancyModel(**kw)


@pytest.fixture(scope="module")
def fitted():
    x, u = data()
    return model(prior=lambda x, u: vdp(x)).fit(x, t=0.01, u=u, x_dot=vdp(x))


def test_hierarchy():
    pairs = [(errors.ShapeError, ValueError), (errors.DataError, ValueError),
             (errors.ParameterError, ValueError), (errors.UnknownNameError, ValueError),
             (errors.NotFittedError, AttributeError), (errors.PriorError, ValueError),
             (errors.ModelFileError, ValueError), (errors.ExportError, ValueError),
             (errors.ConvergenceError, RuntimeError),
             (errors.InfeasibleError, ValueError)]
    for cls, builtin in pairs:
        assert issubclass(cls, DiscrepancyError) and issubclass(cls, builtin)


# ------------------------------------------------------------ non-finite data

@pytest.mark.parametrize("argument, value", [("x", np.nan), ("x", np.inf), ("u", np.nan),
                                             ("u", -np.inf), ("x_dot", np.nan), ("t", np.nan)])
def test_non_finite_data(argument, value):
    x, u = data()
    kw = dict(x=x.copy(), u=u.copy(), x_dot=vdp(x), t=np.arange(200) * 0.01)
    kw[argument][17, ...] = value
    with pytest.raises(DataError) as info:
        model().fit(**kw)
    message = str(info.value)
    assert message.startswith(f"{argument} ") and "finite" in message
    assert "17" in message  # where the bad value is


def test_non_finite_data_in_the_second_trajectory_is_located():
    x, _ = data()
    bad = x.copy()
    bad[5, 1] = np.nan
    with pytest.raises(DataError, match=r"x\[1\].*row 5, column 1"):
        model().fit([x, bad], t=0.01)


# -------------------------------------------------------------------- shapes

@pytest.mark.parametrize("x, expected", [(np.zeros((50, 2, 1)), "x must be 2-D"),
                                         ([[1.0, "a"]], "x must be a numeric array"),
                                         (np.zeros((1, 2)), "x must have at least 2 samples"),
                                         ([], "x must hold at least one trajectory")])
def test_bad_x_shapes(x, expected):
    with pytest.raises(ShapeError, match=expected):
        model().fit(x, t=0.01)


def test_one_dimensional_x_is_one_state_and_3d_gets_a_hint():
    fitted = model(differentiation_method="finite_difference").fit(np.sin(np.arange(50.0)),
                                                                     t=0.01)
    assert fitted.n_states_ == 1
    with pytest.raises(ShapeError, match=r"x must be 2-D"):
        model().fit(np.zeros((5, 5, 5)), t=0.01)


def test_trajectories_with_different_numbers_of_states():
    with pytest.raises(ShapeError, match=r"x\[1\]"):
        model().fit([np.zeros((50, 2)), np.zeros((50, 3))], t=0.01)


def test_x_dot_with_wrong_columns():
    x, _ = data()
    with pytest.raises(ShapeError, match="x_dot must have 2 columns"):
        model().fit(x, t=0.01, x_dot=np.zeros((200, 3)))


def test_u_length_differs_from_x():
    x, u = data()
    with pytest.raises(ShapeError) as info:
        model().fit(x, t=0.01, u=u[:-1])
    message = str(info.value)
    assert message.startswith("u ") and "200 rows" in message and "(199, 1)" in message


def test_u_for_some_trajectories_only():
    x, u = data()
    with pytest.raises(ShapeError, match="u"):
        model().fit([x, x], t=0.01, u=[u, None])


def test_u_list_of_the_wrong_length():
    x, u = data()
    with pytest.raises(ShapeError, match="u must be a list of 2"):
        model().fit([x, x], t=0.01, u=[u])


def test_t_array_of_the_wrong_length():
    x, _ = data()
    with pytest.raises(ShapeError, match="t must be"):
        model().fit(x, t=np.arange(199) * 0.01)


@pytest.mark.parametrize("names, argument", [(["a"], "state_names"), (["a", "a"], "state_names"),
                                             (["a", "b c"], "state_names")])
def test_bad_state_names(names, argument):
    x, _ = data()
    with pytest.raises(ShapeError, match=argument):
        model(state_names=names).fit(x, t=0.01)


# --------------------------------------------------------------------- times

@pytest.mark.parametrize("t, where", [(np.r_[0.0, 0.1, 0.1, *np.arange(3, 200) * 0.1], "t[2]"),
                                      (np.arange(200)[::-1] * 0.1, "t[1]"),
                                      (np.r_[np.arange(100), np.arange(100)] * 0.1, "t[100]")])
def test_non_increasing_t(t, where):
    x, _ = data()
    with pytest.raises(DataError) as info:
        model().fit(x, t=t)
    message = str(info.value)
    assert message.startswith("t must be strictly increasing") and where in message


@pytest.mark.parametrize("step", [0.0, -0.01, np.inf, np.nan])
def test_bad_time_step(step):
    x, _ = data()
    with pytest.raises(DataError, match="t as a time step must be a positive"):
        model().fit(x, t=step)


# ------------------------------------------------------- derivative windows

def test_trajectory_shorter_than_the_derivative_window():
    x, _ = data(m=15)
    with pytest.raises(ShapeError) as info:
        model(differentiation_method=dc.SavitzkyGolay(window_length=21)).fit(x, t=0.01)
    message = str(info.value)
    assert "x has 15 samples" in message and "21" in message and "window" in message


def test_second_trajectory_shorter_than_the_window():
    x, _ = data(m=100)
    with pytest.raises(ShapeError, match="15 samples"):
        model(differentiation_method=dc.SavitzkyGolay(window_length=21)).fit(
            [x, x[:15]], t=0.01)


def test_nonuniform_t_with_a_uniform_only_method():
    x, _ = data()
    t = np.cumsum(np.random.default_rng(1).uniform(0.005, 0.015, 200))
    with pytest.raises(DataError, match="uniformly spaced t"):
        model(differentiation_method="savitzky_golay").fit(x, t=t)


# ---------------------------------------------------------------------- prior

@pytest.mark.parametrize("prior, expected", [
    (lambda x, u: x[:, :1], r"prior must return an array of shape \(200, 2\).*\(200, 1\)"),
    (lambda x, u: x.T, r"prior must return .*\(2, 200\)"),
    (lambda x, u: x[:-1], r"prior must return .*\(199, 2\)"),
    (lambda x, u: np.where(x > 1.5, np.nan, x), "prior returned non-finite values"),
    (lambda x, u: np.full_like(x, np.inf), "prior returned non-finite values"),
    (lambda x, u: 1 / 0, "prior raised ZeroDivisionError"),
], ids=["one_column", "transposed", "short", "nan", "inf", "raises"])
def test_bad_prior_output(prior, expected):
    x, _ = data()  # white noise: the prior is evaluated on x as measured (no smoothing)
    with pytest.raises(PriorError, match=expected):
        model(prior=prior, differentiation_method="finite_difference").fit(x, t=0.01)


def test_bad_prior_output_at_predict_and_simulate():
    def fragile(x, u):  # fine on the training data, NaN far from it
        return np.where(np.abs(x) > 8, np.nan, vdp(x))

    x, _ = data()
    m = model(prior=fragile).fit(x, t=0.01, x_dot=vdp(x))
    with pytest.raises(PriorError, match="prior returned non-finite values"):
        m.predict(np.array([[10.0, 0.0]]))
    with pytest.raises(PriorError, match="prior"):
        m.simulate([10.0, 0.0], np.linspace(0, 1, 5))


@pytest.mark.parametrize("prior, expected", [
    ([symbol("x2")], "prior must have one expression per state"),
    ([symbol("x2"), symbol("y") * 2], r"prior\[1\].*\['y'\]"),
    (["x2", "x1"], r"prior\[0\] must be a sympy expression"),
    (42, "prior must be None or a callable"),
], ids=["count", "unknown_symbol", "strings", "number"])
def test_bad_sympy_prior(prior, expected):
    x, _ = data()
    with pytest.raises(ParameterError, match=expected):
        model(prior=prior).fit(x, t=0.01)


# -------------------------------------------------------------------- library

@pytest.mark.parametrize("library", [dc.PolynomialLibrary(degree=0, include_bias=False),
                                     dc.CustomLibrary(expressions=[])],
                         ids=["polynomial", "custom"])
def test_empty_library(library):
    x, _ = data()
    with pytest.raises(ParameterError) as info:
        model(feature_library=library).fit(x, t=0.01)
    message = str(info.value)
    assert type(library).__name__ in message
    assert "no features" in message or "non-empty list" in message


def test_library_variable_unknown():
    x, _ = data()
    with pytest.raises(UnknownNameError, match="'x3'"):
        model(feature_library=dc.PolynomialLibrary(variables=["x3"])).fit(x, t=0.01)


# ---------------------------------------------------------------- method names

def test_unknown_differentiation_method_lists_the_valid_ones():
    x, _ = data()
    with pytest.raises(UnknownNameError) as info:
        model(differentiation_method="savgol").fit(x, t=0.01)
    message = str(info.value)
    assert "differentiation_method" in message and "'savgol'" in message
    for name in dc.differentiation.available_methods():
        assert name in message


def test_differentiation_method_of_the_wrong_type():
    x, _ = data()
    with pytest.raises(ParameterError, match="differentiation_method must be None or a "
                                             "Differentiator"):
        model(differentiation_method=np.gradient).fit(x, t=0.01)


def test_unknown_score_metric_lists_the_valid_ones(fitted):
    x, u = data()
    with pytest.raises((UnknownNameError, ParameterError)) as info:
        fitted.score(x, t=0.01, u=u, x_dot=vdp(x), metric="mse")
    message = str(info.value)
    assert "metric" in message and "'mse'" in message
    for name in ("r2", "rmse", "trajectory"):
        assert name in message


def test_unknown_export_part(fitted):
    with pytest.raises(ParameterError, match="part"):
        fitted.to_sympy(part="everything")


# --------------------------------------------------------------- model usage

def test_not_fitted():
    x, _ = data()
    for call in (lambda m: m.predict(x), lambda m: m.discrepancy(x),
                 lambda m: m.coefficients(), lambda m: m.simulate([0, 0], [0, 1]),
                 lambda m: m.equations(), lambda m: m.save("never.json")):
        with pytest.raises(NotFittedError, match="fit"):
            call(model())


def test_predict_with_wrong_inputs(fitted):
    x, u = data()
    with pytest.raises(ShapeError, match="u is required"):
        fitted.predict(x)
    with pytest.raises(ShapeError, match="x must have 2 columns"):
        fitted.predict(x[:, :1], u)
    with pytest.raises(ShapeError, match="u must have 200 rows"):
        fitted.predict(x, u[:10])


def test_simulate_with_bad_x0_and_t(fitted):
    with pytest.raises(ShapeError, match="x0"):
        fitted.simulate([0.0, 0.0, 0.0], np.linspace(0, 1, 11), u=lambda t: [0.0])
    with pytest.raises(DataError, match="t must be strictly increasing"):
        fitted.simulate([0.0, 0.0], np.array([0.0, 0.2, 0.1]), u=lambda t: [0.0])
    with pytest.raises(ShapeError, match=r"u\(t\) must return"):
        fitted.simulate([0.0, 0.0], np.linspace(0, 1, 11), u=lambda t: [0.0, 1.0])
    with pytest.raises(ShapeError, match="u must have 11 rows"):
        fitted.simulate([0.0, 0.0], np.linspace(0, 1, 11), u=np.zeros((10, 1)))


def test_u_given_to_a_model_without_inputs():
    x, _ = data()
    m = model().fit(x, t=0.01, x_dot=vdp(x))
    with pytest.raises(ShapeError, match="u was given"):
        m.predict(x, np.zeros((200, 1)))


@pytest.mark.timeout(60, method="signal")  # guards a hang, not speed
def test_simulation_blow_up_is_a_convergence_error():
    x = np.linspace(0.1, 1.0, 50)[:, None]
    m = model(feature_library=dc.PolynomialLibrary(degree=2)).fit(x, t=1.0, x_dot=x**2)
    with pytest.raises(errors.SimulationError, match="stopped at t = 1") as info:
        m.simulate([1.0], np.linspace(0, 2, 21))  # x' = x^2 from 1 blows up at t = 1
    assert isinstance(info.value, errors.ConvergenceError)
    partial, times = info.value.partial, info.value.times
    assert len(times) == len(partial) and times[-1] < 1.0  # the states before the blow-up
    assert np.allclose(partial[:, 0], 1.0 / (1.0 - times), rtol=1e-6)  # exact: 1 / (1 - t)


# ------------------------------------------------------------------ model file

def test_corrupted_model_file(fitted, tmp_path):
    path = tmp_path / "m.json"
    fitted.save(path)
    text = path.read_text()
    path.write_text(text[: len(text) // 3])
    with pytest.raises(ModelFileError, match="model file.*not valid JSON"):
        dc.load_model(path, prior=lambda x, u: vdp(x))


def test_tampered_model_file(tmp_path):
    x, _ = data()
    m = model(prior=[symbol("x2"), -symbol("x1")]).fit(x, t=0.01, x_dot=vdp(x))
    path = tmp_path / "m.json"
    m.save(path)
    doc = json.loads(path.read_text())
    doc["features"][1] = ["sym", "__import__('os')"]
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match=r"features\[1\].*identifier"):
        dc.load_model(path)
    doc["features"][1] = ["sym", "x1"]
    doc["coefficients"][0][0] = "1"
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="coefficients"):
        dc.load_model(path)


def test_messages_describe_values_without_dumping_them():
    big = np.zeros((1000, 3, 2))
    with pytest.raises(ShapeError) as info:
        model().fit(big, t=0.01)
    assert len(str(info.value)) < 300


def test_lasso_that_cannot_converge_warns_and_says_which_target():
    theta = np.random.default_rng(0).normal(size=(50, 5))
    y = np.c_[theta @ np.arange(5.0), theta[:, 0]]
    with pytest.warns(errors.ConvergenceWarning, match=r"target\(s\) \[0\]"):
        opt = dc.Lasso(alpha=1e-6, max_iter=2, tol=1e-12).fit(theta, y)
    assert opt.converged_.tolist() == [False, True]


def test_sympy_expression_with_unsupported_function():
    x, _ = data()
    lib = dc.CustomLibrary(expressions=[sp.gamma(symbol("x1"))])
    with pytest.raises(errors.ExportError, match="gamma"):
        model(feature_library=lib).fit(x, t=0.01)


@pytest.mark.parametrize("t", [[0.0], 3.0], ids=["one_time", "scalar"])
def test_simulate_with_fewer_than_two_times(fitted, t):
    try:
        out = fitted.simulate([0.1, 0.2], t, u=lambda tau: [0.0])
    except (ShapeError, DataError) as e:
        assert "t" in str(e)
    else:  # the only other sensible answer: the initial state itself
        np.testing.assert_array_equal(out, [[0.1, 0.2]])
