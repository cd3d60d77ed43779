"""Model files: exact round trips, and every kind of tampering refused without running anything."""
from __future__ import annotations

import builtins
import copy
import json
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import discrepancy as dc
from discrepancy.errors import DiscrepancyError, ModelFileError, ParameterError
from discrepancy.symbolic import symbol

x1, x2, u = symbol("x1"), symbol("x2"), symbol("u")


def sawtooth(v):
    return v - np.floor(v)


FUNCTIONS = {"sawtooth": sawtooth}


def true_rhs(x, uu):
    return np.column_stack([x[:, 1], -x[:, 0] + 0.4 * x[:, 1] - 0.4 * x[:, 0] ** 2 * x[:, 1]
                            + 0.5 * np.sin(x[:, 0]) * uu[:, 0] + 0.2 * sawtooth(x[:, 1])])


def callable_prior(x, uu):
    return np.column_stack([x[:, 1], -x[:, 0]])


SYMPY_PRIOR = [x2, -x1 + sp.Rational(1, 10) * (1 - x1**2) * x2]


def library(with_function=True):
    lib = (dc.PolynomialLibrary(degree=3, variables=["x1", "x2"])
           + dc.FourierLibrary(variables=["x1"]) * dc.PolynomialLibrary(
               degree=1, include_bias=False, variables=["u"])
           + dc.CustomLibrary(expressions=[sp.exp(-x2**2) / 3, sp.sqrt(1 + x1**2)]))
    if with_function:
        lib = lib + dc.CustomLibrary(functions=FUNCTIONS, variables=["x2"])
    return lib


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(3)
    x, uu = rng.uniform(-2, 2, size=(300, 2)), rng.uniform(-1, 1, size=(300, 1))
    return x, uu


@pytest.fixture(scope="module")
def callable_model(data):
    x, uu = data
    return dc.DiscrepancyModel(prior=callable_prior, feature_library=library(),
                               optimizer=dc.STLSQ(threshold=0.05)).fit(
        x, t=1.0, u=uu, x_dot=true_rhs(x, uu))


@pytest.fixture(scope="module")
def sympy_model(vdp_data):
    return dc.DiscrepancyModel(prior=SYMPY_PRIOR, feature_library=dc.PolynomialLibrary(degree=3),
                               optimizer=dc.STLSQ(threshold=0.05),
                               differentiation_method="savitzky_golay").fit(
        vdp_data.x, t=vdp_data.dt)


@pytest.fixture(scope="module")
def plain_model(lorenz_data):
    return dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=2),
                               optimizer=dc.STLSQ(threshold=0.5)).fit(
        lorenz_data.x, t=lorenz_data.dt, x_dot=lorenz_data.x_dot)


def states(n, seed=0):
    return np.random.default_rng(seed).uniform(-2, 2, size=(100, n))


# ----------------------------------------------------------------- round trips

def test_round_trip_with_a_callable_prior(callable_model, data, tmp_path):
    path = tmp_path / "model.json"
    callable_model.save(path)
    loaded = dc.load_model(path, prior=callable_prior, functions=FUNCTIONS)
    x, uu = states(2), states(1, seed=1)
    np.testing.assert_array_equal(loaded.predict(x, uu), callable_model.predict(x, uu))
    np.testing.assert_array_equal(loaded.discrepancy(x, uu), callable_model.discrepancy(x, uu))
    np.testing.assert_array_equal(loaded.coefficients(), callable_model.coefficients())
    assert loaded.get_feature_names() == callable_model.get_feature_names()
    assert loaded.equations() == callable_model.equations()
    assert loaded.state_names_ == ["x1", "x2"] and loaded.input_names_ == ["u"]
    # the hybrid is still the true system after the round trip
    np.testing.assert_allclose(loaded.predict(x, uu), true_rhs(x, uu), atol=1e-9)


def test_round_trip_with_a_sympy_prior_needs_no_code(sympy_model, tmp_path):
    path = tmp_path / "model.json"
    sympy_model.save(path)
    loaded = dc.load_model(path)
    x = states(2)
    np.testing.assert_array_equal(loaded.predict(x), sympy_model.predict(x))
    assert loaded.to_sympy() == sympy_model.to_sympy()
    t = np.linspace(0, 5, 51)
    np.testing.assert_array_equal(loaded.simulate([0.5, 0.0], t),
                                  sympy_model.simulate([0.5, 0.0], t))


def test_round_trip_without_prior(plain_model, tmp_path):
    path = tmp_path / "lorenz.json"
    plain_model.save(path)
    loaded = dc.load_model(path)
    x = states(3) * 10
    np.testing.assert_array_equal(loaded.predict(x), plain_model.predict(x))
    assert loaded.equations() == plain_model.equations()


def test_round_trip_keeps_coefficients_bit_for_bit(callable_model, tmp_path):
    path = tmp_path / "model.json"
    callable_model.save(path)
    doc = json.loads(path.read_text())
    assert np.array_equal(np.array(doc["coefficients"]), callable_model.coefficients())


def test_callable_prior_must_be_passed_back(callable_model, tmp_path):
    path = tmp_path / "model.json"
    callable_model.save(path)
    with pytest.raises(ParameterError, match="prior"):
        dc.load_model(path, functions=FUNCTIONS)
    with pytest.raises(ParameterError, match="sawtooth"):
        dc.load_model(path, prior=callable_prior)


def test_loading_calls_no_eval_exec_or_sympify(sympy_model, callable_model, tmp_path,
                                               monkeypatch):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    sympy_model.save(a)
    callable_model.save(b)

    def forbidden(*args, **kwargs):
        raise AssertionError("the loader must not evaluate text")

    for module, name in [(builtins, "eval"), (builtins, "exec"), (sp, "sympify"),
                         (sp, "parse_expr"), (sp, "lambdify")]:
        monkeypatch.setattr(module, name, forbidden)
    import sympy.parsing.sympy_parser as parser
    monkeypatch.setattr(parser, "parse_expr", forbidden)
    x = states(2)
    dc.load_model(a).predict(x)
    dc.load_model(b, prior=callable_prior, functions=FUNCTIONS).predict(x, states(1))


# -------------------------------------------------------------------- tampering

@pytest.fixture(scope="module")
def saved(sympy_model, callable_model, tmp_path_factory):
    """The JSON documents of a sympy-prior model and of a callable-prior model with inputs."""
    folder = tmp_path_factory.mktemp("saved")
    docs = {}
    for key, model in (("sympy", sympy_model), ("callable", callable_model)):
        model.save(folder / f"{key}.json")
        docs[key] = json.loads((folder / f"{key}.json").read_text())
    return docs


def load_doc(doc, path, kind="sympy", raw=None):
    path.write_text(raw if raw is not None else json.dumps(doc))
    if kind == "sympy":
        return dc.load_model(path)
    return dc.load_model(path, prior=callable_prior, functions=FUNCTIONS)


def string_leaves(node, path=()):
    if isinstance(node, str):
        yield path
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from string_leaves(v, (*path, i))
    elif isinstance(node, dict):
        for k, v in node.items():
            yield from string_leaves(v, (*path, k))


def replaced(doc, path, value):
    out = copy.deepcopy(doc)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


# free text that is stored for people and never interpreted
FREE_TEXT = {"written_by", "metadata"}


@pytest.mark.parametrize("kind", ["sympy", "callable"])
def test_every_string_replaced_by_code_is_refused_and_never_run(saved, kind, tmp_path):
    marker = tmp_path / "executed"
    codes = [f"__import__('pathlib').Path({str(marker)!r}).touch()",
             f"os.system('touch {marker}')",
             "lambda: 0"]
    doc = saved[kind]
    leaves = list(string_leaves(doc))
    assert len(leaves) > 20
    x, uu = states(2), states(1, seed=1)
    original = load_doc(doc, tmp_path / "orig.json", kind)
    refused = 0
    for path in leaves:
        for code in codes:
            tampered = replaced(doc, path, code)
            free = path[0] in FREE_TEXT or path == ("prior", "name")
            if free:
                model = load_doc(tampered, tmp_path / "t.json", kind)
                args = (x,) if kind == "sympy" else (x, uu)
                np.testing.assert_array_equal(model.predict(*args), original.predict(*args))
            else:
                with pytest.raises(ModelFileError):
                    load_doc(tampered, tmp_path / "t.json", kind)
                refused += 1
    assert refused > 40
    assert not marker.exists()


CODE_NAME = "__import__('os').system('echo hacked')"


def _feature(doc, i, node):
    return replaced(doc, ("features", i), node)


def _active_index(doc):
    """Index of a feature with a non-zero coefficient (so it is compiled on load)."""
    coef = np.array(doc["coefficients"])
    return int(np.flatnonzero(np.any(coef != 0, axis=0))[0])


TAMPERS = {
    "wrong version": lambda d: replaced(d, ("version",), 5),
    "version as text": lambda d: replaced(d, ("version",), "1"),
    "version as true": lambda d: replaced(d, ("version",), True),
    "version as 1.0": lambda d: replaced(d, ("version",), 1.0),
    "wrong format": lambda d: replaced(d, ("format",), "pickle"),
    "missing key": lambda d: {k: v for k, v in d.items() if k != "coefficients"},
    "extra key": lambda d: {**d, "code": "print(1)"},
    "extra key in prior": lambda d: replaced(d, ("prior",), {**d["prior"], "code": "print(1)"}),
    "state name is code": lambda d: replaced(d, ("state_names", 0), CODE_NAME),
    "duplicate state names": lambda d: replaced(d, ("state_names",), ["x1", "x1"]),
    "state names not a list": lambda d: replaced(d, ("state_names",), "x1 x2"),
    "too few coefficient rows": lambda d: replaced(d, ("coefficients",), d["coefficients"][:1]),
    "too many coefficient rows": lambda d: replaced(d, ("coefficients",),
                                                    d["coefficients"] * 2),
    "short coefficient row": lambda d: replaced(d, ("coefficients", 1),
                                                d["coefficients"][1][:-1]),
    "coefficients transposed": lambda d: replaced(d, ("coefficients",),
                                                  np.array(d["coefficients"]).T.tolist()),
    "infinite coefficient": lambda d: replaced(d, ("coefficients", 1, 2), float("inf")),
    "coefficient as text": lambda d: replaced(d, ("coefficients", 1, 2), "0.4"),
    "coefficient as bool": lambda d: replaced(d, ("coefficients", 1, 2), True),
    "coefficient as list": lambda d: replaced(d, ("coefficients", 1, 2), [0.4]),
    "no features": lambda d: replaced(d, ("features",), []),
    "features not a list": lambda d: replaced(d, ("features",), {"0": ["sym", "x1"]}),
    "unknown node": lambda d: _feature(d, 1, ["lambda", ["sym", "x1"]]),
    "unknown node in prior": lambda d: replaced(d, ("prior", "expressions", 0),
                                                ["call", "os.system", "ls"]),
    "symbol name is code": lambda d: _feature(d, 1, ["sym", CODE_NAME]),
    "symbol not a variable": lambda d: _feature(d, 1, ["sym", "y"]),
    "symbol of the prior not a variable": lambda d: replaced(d, ("prior", "expressions", 0),
                                                             ["sym", "y"]),
    "function name is code": lambda d: _feature(d, 1, ["fn", CODE_NAME, ["sym", "x1"]]),
    "undeclared function in an active term": lambda d: _feature(
        d, _active_index(d), ["fn", "system", ["sym", "x1"]]),
    "undeclared function in an inactive term": lambda d: _feature(
        d, 0, ["fn", "system", ["sym", "x1"]]),
    "known function with two arguments": lambda d: _feature(d, 1, ["fn", "sin", ["sym", "x1"],
                                                                   ["sym", "x2"]]),
    "zero denominator": lambda d: _feature(d, 1, ["num", 1, 0]),
    "rational of floats": lambda d: _feature(d, 1, ["num", 1.5, 2]),
    "float as text": lambda d: _feature(d, 1, ["float", "nan"]),
    "infinite float": lambda d: _feature(d, 1, ["float", float("inf")]),
    "add with one operand": lambda d: _feature(d, 1, ["add", ["sym", "x1"]]),
    "pow with three operands": lambda d: _feature(d, 1, ["pow", ["sym", "x1"], ["num", 2, 1],
                                                         ["num", 2, 1]]),
    "node not a list": lambda d: _feature(d, 1, {"sym": "x1"}),
    "empty node": lambda d: _feature(d, 1, []),
    "deep nesting": lambda d: _feature(d, 1, _nested(100)),
    "prior kind unknown": lambda d: replaced(d, ("prior", "kind"), "python"),
    "prior expressions wrong count": lambda d: replaced(d, ("prior", "expressions"),
                                                        d["prior"]["expressions"][:1]),
    "prior not an object": lambda d: replaced(d, ("prior",), "lambda x, u: x"),
    "top level is a list": lambda d: [d],
}


def _nested(depth):
    node = ["sym", "x1"]
    for _ in range(depth):
        node = ["add", node, ["num", 1, 1]]
    return node




@pytest.mark.parametrize("name", sorted(TAMPERS))
def test_tampered_file_is_refused(saved, name, tmp_path):
    tampered = TAMPERS[name](saved["sympy"])
    with pytest.raises(ModelFileError):
        load_doc(tampered, tmp_path / "t.json")


def test_function_names_in_the_callable_model_file(saved, tmp_path):
    doc = saved["callable"]
    with pytest.raises(ModelFileError):
        load_doc(replaced(doc, ("user_functions", 0), CODE_NAME), tmp_path / "t.json", "callable")
    with pytest.raises(ModelFileError):
        load_doc(replaced(doc, ("user_functions",), "sawtooth"), tmp_path / "t.json", "callable")


def test_nan_coefficient_is_refused(saved, tmp_path):
    doc = saved["sympy"]
    row = json.dumps(doc["coefficients"][0])
    text = json.dumps(doc).replace(row, "[NaN" + row[row.index(","):], 1)
    assert "NaN" in text
    with pytest.raises(ModelFileError, match="coefficients"):
        load_doc(None, tmp_path / "t.json", raw=text)
    # an overflowing literal parses as inf
    text = json.dumps(doc).replace(row, "[1e999" + row[row.index(","):], 1)
    with pytest.raises(ModelFileError, match="coefficients"):
        load_doc(None, tmp_path / "t.json", raw=text)


@pytest.mark.parametrize("raw", ["", "{", "not json", "null", "[]", "{}", '{"format": 1}'],
                         ids=["empty", "truncated", "text", "null", "list", "empty object",
                              "few keys"])
def test_not_a_model_file(raw, tmp_path):
    with pytest.raises(ModelFileError, match="model file"):
        load_doc(None, tmp_path / "t.json", raw=raw)


def test_truncated_file_is_refused(saved, tmp_path):
    text = json.dumps(saved["sympy"])
    for cut in (10, len(text) // 2, len(text) - 1):
        with pytest.raises(ModelFileError):
            load_doc(None, tmp_path / "t.json", raw=text[:cut])


def test_binary_garbage_is_refused(tmp_path):
    path = tmp_path / "t.json"
    path.write_bytes(b"\x80\x81\xfe\xff" * 10)
    with pytest.raises(ModelFileError):
        dc.load_model(path)


def test_json_nested_beyond_the_parser_is_refused(tmp_path):
    with pytest.raises(ModelFileError):
        load_doc(None, tmp_path / "t.json", raw="[" * 100000 + "]" * 100000)


def test_huge_integer_literal_is_refused(saved, tmp_path):
    doc = _feature(saved["sympy"], 1, ["num", 1, 1])
    text = json.dumps(doc).replace('["num", 1, 1]', '["num", ' + "7" * 5000 + ", 1]", 1)
    with pytest.raises(ModelFileError):
        load_doc(None, tmp_path / "t.json", raw=text)


def test_huge_power_is_refused_quickly(saved, tmp_path):
    """A 60-byte node 7^(10^9) must not make the loader compute a billion-digit integer."""
    doc = _feature(saved["sympy"], 1, ["pow", ["num", 7, 1], ["num", 10**9, 1]])
    path = tmp_path / "t.json"
    path.write_text(json.dumps(doc))
    script = ("import sys, discrepancy as dc\n"
              "from discrepancy.errors import ModelFileError\n"
              "try:\n    dc.load_model(sys.argv[1])\n"
              "except ModelFileError:\n    sys.exit(0)\n"
              "sys.exit(3)\n")
    try:
        done = subprocess.run([sys.executable, "-c", script, str(path)], timeout=60,
                              capture_output=True)
    except subprocess.TimeoutExpired:
        pytest.fail("loading a model file with a huge integer power did not finish in 15 s")
    assert done.returncode == 0, done.stderr.decode()[-500:]


# ------------------------------------------------------------------ properties

SYMBOLS = [x1, x2, u]
atoms = st.one_of(st.sampled_from(SYMBOLS), st.integers(-5, 5).map(sp.Integer),
                  st.fractions(min_value=-3, max_value=3, max_denominator=7).map(sp.Rational),
                  st.floats(-10, 10, allow_nan=False, allow_subnormal=False).map(sp.Float))


def _combine(children):
    unary = st.sampled_from([sp.sin, sp.cos, sp.exp, sp.tanh, sp.Abs, sp.atan])
    return st.one_of(
        st.lists(children, min_size=2, max_size=3).map(lambda a: sp.Add(*a)),
        st.lists(children, min_size=2, max_size=3).map(lambda a: sp.Mul(*a)),
        st.tuples(children, st.integers(-3, 4)).map(lambda a: sp.Pow(a[0], a[1])),
        st.tuples(unary, children).map(lambda a: a[0](a[1])))


expressions = st.recursive(atoms, _combine, max_leaves=8)


@given(expr=expressions)
def test_expression_data_round_trip(expr):
    from discrepancy.symbolic import from_data, to_data

    assume(not expr.has(sp.zoo, sp.nan, sp.oo, -sp.oo))
    # sympy Floats have an unbounded exponent; files store doubles
    assume(all(f == 0 or 1e-300 < abs(f) < 1e300 for f in expr.atoms(sp.Float)))
    data = to_data(expr)
    assert json.loads(json.dumps(data)) == data   # plain JSON
    assert from_data(json.loads(json.dumps(data))) == expr


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=6), c, max_size=3),
    max_leaves=8)


def all_paths(node, path=()):
    yield path
    if isinstance(node, list):
        for i, v in enumerate(node):
            yield from all_paths(v, (*path, i))
    elif isinstance(node, dict):
        for k, v in node.items():
            yield from all_paths(v, (*path, k))


@settings(max_examples=150)
@given(data=st.data())
def test_random_edits_give_a_model_or_a_model_file_error(saved, tmp_path_factory, data):
    kind = data.draw(st.sampled_from(["sympy", "callable"]))
    doc = saved[kind]
    path = data.draw(st.sampled_from([p for p in all_paths(doc) if p]))
    value = data.draw(json_values)
    tampered = replaced(doc, path, value)
    target = tmp_path_factory.mktemp("fuzz") / "t.json"
    try:
        model = load_doc(tampered, target, kind)
    except ModelFileError:
        return
    except ParameterError as e:  # only legitimate when the file now asks for code
        assert "prior" in str(e) or "functions" in str(e), e
        return
    # whatever loaded must evaluate to finite numbers or raise a package error
    x = states(len(model.state_names_))
    args = (x,) if not model.input_names_ else (x, states(len(model.input_names_)))
    try:
        model.predict(*args)
    except (DiscrepancyError, FloatingPointError):
        pass


# ------------------------------------------------------------ versions and safe saves

def test_version_1_files_still_load(sympy_model, tmp_path):
    """A file as version 1 wrote it (no optimizer, differentiation or fit fields)."""
    doc = sympy_model.to_state()
    old = {k: doc[k] for k in ("format", "written_by", "state_names", "input_names",
                               "features", "coefficients", "prior", "user_functions",
                               "metadata")}
    old["version"] = 1
    (tmp_path / "v1.json").write_text(json.dumps(old))
    loaded = dc.load_model(tmp_path / "v1.json")
    x = states(2)
    np.testing.assert_array_equal(loaded.predict(x), sympy_model.predict(x))


def test_components_are_stored_and_rebuilt(sympy_model, tmp_path):
    sympy_model.save(tmp_path / "m.json")
    doc = json.loads((tmp_path / "m.json").read_text())
    assert doc["differentiation_method"] == {"name": "savitzky_golay", "params": {
        "window_length": 21, "polyorder": 3, "smooth": True}}
    assert doc["optimizer"]["name"] == "stlsq" and doc["optimizer"]["params"]["threshold"] == 0.05
    loaded = dc.load_model(tmp_path / "m.json")
    assert isinstance(loaded.differentiation_method_, dc.SavitzkyGolay)
    assert loaded.optimizer_.threshold == 0.05


@pytest.mark.parametrize("field, value", [
    ("optimizer", {"name": "stlsq", "params": {"threshold": -1}}),
    ("optimizer", {"name": "__import__", "params": {}}),
    ("differentiation_method", {"name": "savitzky_golay", "params": {"window_length": 4}}),
    ("differentiation_method", {"name": "spline", "params": {"s": "os.system('x')"}}),
    ("fit", {"n_samples": "many"}),
])
def test_bad_stored_components_are_refused(sympy_model, tmp_path, field, value):
    doc = sympy_model.to_state()
    doc[field] = value
    (tmp_path / "m.json").write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match=field):
        dc.load_model(tmp_path / "m.json")


def test_constants_that_are_not_finite_reals_are_refused(sympy_model, tmp_path):
    for constant in (["fn", "log", ["num", 0, 1]], ["pow", ["num", 0, 1], ["num", -1, 1]],
                     ["fn", "log", ["num", -1, 1]]):
        doc = sympy_model.to_state()
        doc["features"][0] = constant
        (tmp_path / "m.json").write_text(json.dumps(doc))
        with pytest.raises(ModelFileError, match="not a finite real"):
            dc.load_model(tmp_path / "m.json")


_SAVE_UNDER_LIMIT = """
import resource, sys
import numpy as np
import discrepancy as dc
x = np.random.default_rng(0).uniform(-1, 1, (200, 2))
model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(6),
                            optimizer=dc.STLSQ(threshold=0)).fit(x, t=1.0, x_dot=x[:, ::-1])
resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))   # the new file cannot be written
try:
    model.save(sys.argv[1])
except dc.errors.ModelFileError as e:
    print("refused:", e)
"""


def test_a_failing_save_keeps_the_previous_file(plain_model, tmp_path):
    path = tmp_path / "model.json"
    plain_model.save(path)
    good = path.read_bytes()
    out = subprocess.run([sys.executable, "-c", _SAVE_UNDER_LIMIT, str(path)],
                         capture_output=True, text=True, timeout=120)
    assert "refused: cannot write" in out.stdout, out.stderr
    assert path.read_bytes() == good
    assert [p.name for p in tmp_path.iterdir()] == ["model.json"]  # no temporary left


_SAVE_FOREVER = """
import os, sys, time
import discrepancy.models.files.model_file as mf
real = os.fsync
def slow_fsync(fd):           # the new content is written but not yet in place
    print("writing", flush=True)
    time.sleep(60)
mf.os.fsync = slow_fsync
doc = {"format": "discrepancy-model", "big": "x" * 100000}
mf.write_json(sys.argv[1], doc)
"""


def test_a_save_killed_midway_keeps_the_previous_file(plain_model, tmp_path):
    path = tmp_path / "model.json"
    plain_model.save(path)
    good = path.read_bytes()
    proc = subprocess.Popen([sys.executable, "-c", _SAVE_FOREVER, str(path)],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "writing"
    proc.kill()
    proc.wait(timeout=30)
    assert path.read_bytes() == good
    assert dc.load_model(path).coef_.tolist() == plain_model.coef_.tolist()


def test_saving_to_a_folder_or_a_missing_folder_is_a_clear_error(plain_model, tmp_path):
    with pytest.raises(ModelFileError, match="is a folder"):
        plain_model.save(tmp_path)
    with pytest.raises(ModelFileError, match="cannot write"):
        plain_model.save(tmp_path / "missing" / "m.json")


def test_oversized_files_are_refused_before_parsing(tmp_path):
    from discrepancy.models.files import model_file

    path = tmp_path / "big.json"
    with open(path, "w") as f:
        f.write("[" + " " * (model_file.MAX_BYTES + 10) + "]")
    with pytest.raises(ModelFileError, match="bytes is more than"):
        dc.load_model(path)
