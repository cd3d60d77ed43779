"""The tape evaluator behind ``compile_numpy``: bit for bit the values of a direct tree walk
(the evaluator it replaced, written out below as the reference), close to sympy's own
``lambdify`` and to values known by hand, with repeated subexpressions computed once."""
from __future__ import annotations

import pickle

import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import ExportError, FeatureError
from discrepancy.expression_tape import compile_numpy_many
from discrepancy.symbolic import FUNCTIONS, NARY_FUNCTIONS, compile_numpy, symbol

x, y, z = symbol("x"), symbol("y"), symbol("z")
NAMES = ["x", "y", "z"]


def tree_walk(e, Z):
    """The reference: every node evaluated from its children, recursively (the previous
    ``compile_numpy``, minus user functions)."""
    if e.is_Symbol:
        return Z[:, NAMES.index(e.name)]
    if e.is_number:
        return np.full(Z.shape[0], float(e))
    args = [tree_walk(a, Z) for a in e.args]
    if e.is_Pow:
        if e.args[1].is_Integer and int(e.args[1]) == 2:
            return np.square(args[0])
        return np.power(args[0], float(e.args[1]) if e.args[1].is_number else args[1])
    op = np.add if e.is_Add else np.multiply if e.is_Mul else None
    name = type(e).__name__
    op = op or (NARY_FUNCTIONS[name][1] if name in NARY_FUNCTIONS else None)
    if op is None:
        return FUNCTIONS[name][1](args[0])
    out = args[0]
    for a in args[1:]:
        out = op(out, a)
    return out


EXPRESSIONS = [
    3 * x * sp.sin(x - y) + sp.cos(x - y) ** 2 - 0.7 * y * z ** 3 + sp.Rational(1, 3),
    (2 * sp.cos(x - y) + 0.25) / (1.5 - sp.cos(x - y) ** 2 * sp.sin(z)),
    sp.exp(-x ** 2) * sp.tanh(y) + sp.Abs(z) ** 1.5 + sp.sign(x) * sp.atan(y * z),
    sp.Min(x, y, 0.5) + sp.Max(x * y, -z) + sp.log(1 + x ** 2) + sp.sqrt(2 + sp.sin(y)),
    sp.Abs(x) ** y + 2 ** z + sp.sinh(x) * sp.cosh(y) - sp.tan(z / 4) + sp.pi * x,
    x * y * z + x * y - x * y * z * sp.sin(x * y) + sp.asin(sp.tanh(z)) * sp.acos(sp.tanh(y)),
]


@pytest.fixture(scope="module")
def rows():
    return np.random.default_rng(0).uniform(-2, 2, (500, 3))


@pytest.mark.parametrize("expr", EXPRESSIONS, ids=range(len(EXPRESSIONS)))
def test_bit_for_bit_the_tree_walk_and_close_to_lambdify(expr, rows):
    with np.errstate(all="ignore"):
        got = compile_numpy(expr, NAMES)(rows)
        want = tree_walk(expr, rows)
        peer = sp.lambdify((x, y, z), expr, "numpy")(*rows.T)
    assert got.shape == (500,)
    np.testing.assert_array_equal(got, want)
    finite = np.isfinite(peer)
    assert finite.mean() > 0.5
    np.testing.assert_allclose(got[finite], peer[finite], rtol=1e-12, atol=1e-12)


def test_many_expressions_share_steps_and_equal_the_tree_walk(rows):
    compiled = compile_numpy_many(EXPRESSIONS[:2], NAMES)
    counts = [len(compile_numpy_many([e], NAMES)._steps) for e in EXPRESSIONS[:2]]
    assert len(compiled._steps) < sum(counts)          # cos(x - y) and more, once
    with np.errstate(all="ignore"):
        for got, e in zip(compiled(rows), EXPRESSIONS[:2], strict=True):
            np.testing.assert_array_equal(got, tree_walk(e, rows))


def test_known_values_by_hand():
    Z = np.array([[0.0, 1.0, 2.0], [np.pi / 2, 0.0, -1.0]])
    f = compile_numpy(2 * sp.sin(x) + y ** 2 - z ** 3 + 0.5, NAMES)
    np.testing.assert_allclose(f(Z), [0 + 1 - 8 + 0.5, 2 + 0 + 1 + 0.5], rtol=1e-15)
    np.testing.assert_array_equal(compile_numpy(sp.Float(2.5), NAMES)(Z), [2.5, 2.5])
    assert compile_numpy(-sp.Float(0.0) * 1, NAMES)(Z).tolist() == [0.0, 0.0]
    assert compile_numpy(y, NAMES)(Z).tolist() == [1.0, 0.0]


def test_repeated_outputs_are_separate_arrays_and_constants_are_fresh(rows):
    a, b, c = compile_numpy_many([x * y, x * y, sp.Float(3.0)], NAMES)(rows)
    a[:] = 0.0
    assert np.all(b == rows[:, 0] * rows[:, 1])
    c[:] = 0.0
    assert np.all(compile_numpy_many([sp.Float(3.0)], NAMES)(rows)[0] == 3.0)


def test_user_functions_run_once_per_occurrence_and_errors_are_named():
    calls = []

    def clipped(v):
        calls.append(1)
        return np.clip(v, -1, 1)

    g = sp.Function("g")
    f = compile_numpy(g(x) + g(x) ** 3, NAMES, {"g": clipped})
    Z = np.array([[3.0, 0, 0], [-0.5, 0, 0]])
    np.testing.assert_array_equal(f(Z), [2.0, -0.625])
    assert len(calls) == 2                      # as written: a user function may keep state
    h = compile_numpy(g(x) * g(y), NAMES, {"g": lambda v: 1 / 0})
    with pytest.raises(FeatureError, match="user function 'g' raised ZeroDivisionError"):
        h(Z)
    with pytest.raises(ExportError, match="not one of"):
        compile_numpy(symbol("w") + x, NAMES)
    with pytest.raises(ExportError, match="not a supported function"):
        compile_numpy(sp.gamma(x), NAMES)


def test_pickles_and_a_lagrangian_system_keeps_its_analytic_pendulum(rows):
    f = pickle.loads(pickle.dumps(compile_numpy_many(EXPRESSIONS[:2], NAMES)))
    np.testing.assert_array_equal(f(rows)[1], compile_numpy(EXPRESSIONS[1], NAMES)(rows))
    phi, dphi = symbol("phi"), symbol("dphi")
    pendulum = dc.systems.LagrangianSystem(0.5 * 2.0 * 0.3 ** 2 * dphi ** 2,
                                           -2.0 * 9.81 * 0.3 * sp.cos(phi), ["phi"],
                                           dissipation=0.5 * 0.1 * dphi ** 2)
    state = np.array([[0.4, -1.2], [2.0, 0.3]])
    acc = -9.81 / 0.3 * np.sin(state[:, 0]) - 0.1 / (2.0 * 0.3 ** 2) * state[:, 1]
    np.testing.assert_allclose(pendulum.rhs(state), np.c_[state[:, 1], acc], rtol=1e-14)
