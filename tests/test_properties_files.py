"""Property tests (hypothesis): file loading and model-file expressions round-trip exactly."""
import h5py
import numpy as np
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from discrepancy import io
from discrepancy.symbolic import FUNCTIONS, compile_numpy, from_data, symbol, to_data

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, width=64)
tables = st.integers(2, 40).flatmap(
    lambda m: st.integers(1, 5).flatmap(lambda n: arrays(np.float64, (m, n), elements=finite)))


@given(table=tables)
def test_npz_and_hdf5_round_trip_any_table(tmp_path_factory, table):
    d = tmp_path_factory.mktemp("io")
    t = np.arange(len(table)) * 0.5
    np.savez(d / "a.npz", t=t, x=table)
    with h5py.File(d / "a.h5", "w") as f:
        f["x"], f["t"] = table, t
    for path in (d / "a.npz", d / "a.h5"):
        loaded = io.load(path)
        np.testing.assert_array_equal(loaded.x, table)
        np.testing.assert_array_equal(loaded.t, t)


@given(table=tables)
def test_csv_round_trip_to_printed_precision(tmp_path_factory, table):
    d = tmp_path_factory.mktemp("csv")
    t = np.arange(len(table)) * 0.25
    names = [f"c{j}" for j in range(table.shape[1])]
    np.savetxt(d / "a.csv", np.c_[t, table], delimiter=",", header=",".join(["t", *names]),
               comments="", fmt="%.17g")
    loaded = io.load(d / "a.csv")
    np.testing.assert_array_equal(loaded.x, table)
    assert loaded.state_names == names


X = [symbol(n) for n in ("x1", "x2", "u")]
leaves = st.sampled_from(X) | st.integers(-5, 5).map(sp.Integer) | st.fractions(
    min_value=-3, max_value=3, max_denominator=7).map(sp.Rational)


def _grow(children):
    unary = st.tuples(st.sampled_from(sorted(set(FUNCTIONS) - {"log", "acos", "asin"})),
                      children).map(lambda fa: FUNCTIONS[fa[0]][0](fa[1]))
    return (st.tuples(children, children).map(lambda ab: ab[0] + ab[1])
            | st.tuples(children, children).map(lambda ab: ab[0] * ab[1])
            | st.tuples(children, st.integers(1, 4)).map(lambda be: be[0] ** be[1])
            | unary)


expressions = st.recursive(leaves, _grow, max_leaves=8)


@given(expr=expressions)
def test_expression_data_round_trip_is_exact(expr):
    rebuilt = from_data(to_data(expr))
    assert sp.simplify(rebuilt - expr) == 0 or rebuilt == expr


@given(expr=expressions, z=arrays(np.float64, (7, 3), elements=st.floats(-2, 2, width=64)))
def test_compiled_expression_matches_sympy_evaluation(expr, z):
    f = compile_numpy(expr, ["x1", "x2", "u"])
    with np.errstate(all="ignore"):
        got = np.broadcast_to(f(z), (7,))
    for row, value in zip(z, got, strict=True):
        exact = complex(expr.subs(dict(zip(X, map(sp.Float, row), strict=True))).evalf())
        if abs(exact.imag) > 1e-9 or not np.isfinite(abs(exact)) or abs(exact) > 1e12:
            continue
        assert np.isclose(value, exact.real, rtol=1e-7, atol=1e-9), (expr, row)
