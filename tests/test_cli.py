"""The command line, run as a user would (in-process through main, and once as a subprocess)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from discrepancy.cli import main
from discrepancy.errors import ParameterError
from discrepancy.libraries.spec import parse_library

PRIOR = '''import numpy as np
def f_m(x, u=None):
    return np.c_[x[:, 1], 0.1 * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]]
'''


@pytest.fixture
def vdp_files(tmp_path, vdp_data):
    x = vdp_data.x + 0.005 * np.random.default_rng(0).standard_normal(vdp_data.x.shape)
    np.savetxt(tmp_path / "run.csv", np.c_[vdp_data.t, x], delimiter=",", header="t,x1,x2",
               comments="")
    (tmp_path / "prior.py").write_text(PRIOR)
    return tmp_path


def test_fit_show_simulate_round_trip(vdp_files, vdp_validation, capsys):
    d = vdp_files
    assert main(["fit", "--data", str(d / "run.csv"), "--prior", f"{d / 'prior.py'}:f_m",
                 "--library", "poly(3)", "--differentiation", "savitzky_golay(window_length=31)",
                 "--optimizer", "stlsq(threshold=0.05)", "--out", str(d / "m.json")]) == 0
    out = capsys.readouterr().out
    assert "(x2)' = prior + 0.4" in out
    doc = json.loads((d / "m.json").read_text())
    names = ["1", "x1", "x2"]
    assert doc["state_names"] == ["x1", "x2"] and len(doc["features"]) == 10 and names
    assert doc["differentiation_method"] == {"name": "savitzky_golay", "params": {
        "window_length": 31, "polyorder": 3, "smooth": True}}
    assert main(["show", str(d / "m.json"), "--latex"]) == 0
    assert "x_{1}^{2} x_{2}" in capsys.readouterr().out
    assert main(["simulate", "--model", str(d / "m.json"), "--prior", f"{d / 'prior.py'}:f_m",
                 "--x0=-0.2,-0.3", "--t", "0:25:0.01", "--out", str(d / "sim.csv")]) == 0
    sim = np.loadtxt(d / "sim.csv", delimiter=",", skiprows=1)
    err = np.linalg.norm(sim[:, 1:] - vdp_validation.x) / np.linalg.norm(vdp_validation.x)
    assert err < 0.01


def test_errors_are_reported_not_raised(vdp_files, capsys):
    d = vdp_files
    assert main(["fit", "--data", str(d / "run.csv"), "--library", "poly(3)+"]) == 2
    assert "library spec" in capsys.readouterr().err
    assert main(["simulate", "--model", str(d / "run.csv"), "--x0", "1,2", "--t", "0:1:0.1"]) == 1
    assert "model file" in capsys.readouterr().err


@pytest.mark.parametrize("option, value, expected", [
    ("--differentiation", "savitzky_golay(window_length=4)", "odd integer"),
    ("--differentiation", "spline(order=9)", "order must be an integer >= 1 and <= 5"),
    ("--differentiation", "bogus", "valid names"),
    ("--optimizer", "stlsq(threshold=-1)", "threshold must be"),
    ("--optimizer", "stlsq(threshold=__import__('os'))", "literal"),
])
def test_fit_options_go_through_the_registries_and_constraints(vdp_files, capsys, option,
                                                                value, expected):
    d = vdp_files
    assert main(["fit", "--data", str(d / "run.csv"), option, value]) == 2
    err = capsys.readouterr().err
    assert expected in err and err.count("\n") == 1


def test_threshold_auto_and_any_method_options_are_used(vdp_files, capsys):
    d = vdp_files
    assert main(["fit", "--data", str(d / "run.csv"), "--library", "poly(3)",
                 "--optimizer", "stlsq(threshold=auto)", "--differentiation", "spline(s=0.1)",
                 "--out", str(d / "m.json")]) == 0
    doc = json.loads((d / "m.json").read_text())
    assert doc["optimizer"]["params"]["threshold"] == "auto"
    assert doc["differentiation_method"] == {"name": "spline",
                                             "params": {"s": 0.1, "order": 3, "smooth": True}}


def test_console_script_help_lists_commands():
    out = subprocess.run([sys.executable, "-m", "discrepancy.cli", "--help"], capture_output=True,
                         text=True, check=True).stdout
    for command in ("reproduce", "fit", "simulate", "show"):
        assert command in out


def test_library_spec_parser_builds_the_stated_library():
    lib = parse_library("poly(1) + fourier(1, x1) * poly(1, u)").fit(["x1", "x2", "u"])
    assert lib.get_feature_names() == ["1", "x1", "x2", "u", "sin(x1)", "sin(x1) u",
                                       "cos(x1)", "cos(x1) u"]
    for bad in ["poly", "poly(x)", "spline(2)", "poly(2) poly(3)", "poly(2,", "__import__(1)"]:
        with pytest.raises(ParameterError):
            parse_library(bad)


def test_reproduce_without_the_paper_package_says_how_to_install_it(monkeypatch, capsys):
    import importlib.metadata

    monkeypatch.setattr(importlib.metadata, "entry_points", lambda group: [])
    assert main(["reproduce", "vdp-parameter", "--out", "x"]) == 2
    err = capsys.readouterr().err
    assert "pip install -e paper" in err and err.count("\n") == 1


def test_the_library_imports_nothing_of_the_paper_package():
    import ast
    from pathlib import Path

    import discrepancy

    for path in Path(discrepancy.__file__).parent.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            assert not any(n.startswith("discrepancy_paper") for n in names), path


def test_simulate_takes_inputs_and_times_from_a_file(tmp_path, capsys):
    """A forced oscillator x'' = -x + u fitted with its input; simulated from a file of input
    samples (times from its t column) with the fast fixed-step method, it matches the exact
    solution of the forced system; a model with inputs and no --inputs is refused."""
    t = np.arange(2001) * 0.01
    u = np.sin(0.7 * t)
    exact = np.c_[(np.sin(0.7 * t) - 0.7 * np.sin(t)) / (1 - 0.49),
                  0.7 * (np.cos(0.7 * t) - np.cos(t)) / (1 - 0.49)]
    np.savetxt(tmp_path / "run.csv", np.c_[t, exact, u], delimiter=",", header="t,x1,x2,u",
               comments="")
    np.savetxt(tmp_path / "u.csv", np.c_[t, u], delimiter=",", header="t,u", comments="")
    assert main(["fit", "--data", str(tmp_path / "run.csv"), "--inputs", "u",
                 "--library", "poly(1)", "--optimizer", "stlsq(threshold=0.05)",
                 "--out", str(tmp_path / "m.json")]) == 0
    capsys.readouterr()
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--x0=0,0", "--inputs",
                 str(tmp_path / "u.csv"), "--method", "rk4", "--out",
                 str(tmp_path / "sim.csv")]) == 0
    sim = np.loadtxt(tmp_path / "sim.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(sim[:, 0], t)
    assert np.abs(sim[:, 1:] - exact).max() < 1e-3 * np.abs(exact).max()
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--x0=0,0", "--t",
                 "0:1:0.1"]) == 2
    assert "--inputs is required" in capsys.readouterr().err
