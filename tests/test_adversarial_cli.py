"""Adversarial rows for the command line: every error is one line on stderr starting with
``error:``, exit code 2 for bad arguments and 1 for failures, never a traceback; the rows
run ``discrepancy.cli.main`` in-process (see ``adversarial.py`` for the machinery)."""
from __future__ import annotations

import contextlib
import io
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import discrepancy as dc
from adversarial import Case, check, params, raises, returns
from discrepancy.cli import main
from discrepancy.errors import ParameterError

DIR = Path(tempfile.mkdtemp(prefix="adversarial-cli-"))
T = np.arange(300) * 0.01
X = np.c_[np.sin(T), np.cos(T)]
np.savetxt(DIR / "run.csv", np.c_[T, X], delimiter=",", header="t,x1,x2", comments="")
np.savetxt(DIR / "untimed.csv", X, delimiter=",", header="x1,x2", comments="")
np.savetxt(DIR / "nan.csv", np.c_[T, np.where(T[:, None] > 2, np.nan, X)], delimiter=",",
           header="t,x1,x2", comments="")
(DIR / "prior.py").write_text("import numpy as np\ndef f(x, u=None):\n    return np.c_[x[:, 1], "
                              "-x[:, 0]]\ndef bad(x, u=None):\n    return x[:, :1]\n")
(DIR / "broken.py").write_text("def f(x, u=None):\n    return x +\n")
(DIR / "folder").mkdir()
RUN, PRIOR = str(DIR / "run.csv"), str(DIR / "prior.py")
FIT = ["fit", "--data", RUN, "--differentiation", "finite_difference", "--optimizer",
       "stlsq(threshold=0.05)"]
dc.DiscrepancyModel(differentiation_method="finite_difference").fit(X, 0.01).save(DIR / "plain.json")
dc.DiscrepancyModel(prior=lambda x, u: x, differentiation_method="finite_difference").fit(
    X, 0.01).save(DIR / "callable.json")
MODEL = str(DIR / "plain.json")
dc.DiscrepancyModel.from_prior([0.9 * dc.symbolic.symbol("x")], state_names=["x"],
                               discrete_time=True).save(DIR / "map.json")


@dataclass(frozen=True)
class Run:
    code: int
    out: str
    err: str


def cli(*argv) -> Run:
    """``discrepancy *argv`` in-process: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as e:  # argparse's usage errors
            code = e.code
    return Run(code, out.getvalue(), err.getvalue())


def fails(code: int, pattern: str):
    """Exit ``code`` with one line ``error: ...`` matching ``pattern`` and no traceback."""
    def ok(run: Run) -> bool:
        lines = run.err.strip().splitlines()
        assert run.code == code and len(lines) == 1 and lines[0].startswith("error: "), run
        assert "Traceback" not in run.err and re.search(pattern, lines[0]), run
        return True
    return returns(ok)


def out(name):
    return str(DIR / name)


CASES = [
    Case("cli", "fit: missing data file", lambda: cli(*FIT[:2], out("none.csv"), "--out", out("m.json")), fails(1, r"data file '.*none.csv' does not exist")),
    Case("cli", "fit: data a folder", lambda: cli("fit", "--data", DIR / "folder", "--out", out("m.json")), fails(1, r"data file '.*folder' is a folder, not a file")),
    Case("cli", "fit: data of an unknown type", lambda: cli("fit", "--data", PRIOR), fails(2, r"unknown file type '.py'")),
    Case("cli", "fit: data with NaN", lambda: cli("fit", "--data", DIR / "nan.csv", "--out", out("m.json")), fails(1, r"nan.csv states must be finite; found nan at row 201")),
    Case("cli", "fit: library unclosed", lambda: cli(*FIT, "--library", "poly(3)+"), fails(2, r"library spec 'poly\(3\)\+'")),
    Case("cli", "fit: library with code", lambda: cli(*FIT, "--library", "__import__('os').system('ls')"), fails(2, r"library spec")),
    Case("cli", "fit: unknown optimizer", lambda: cli(*FIT[:5], "--optimizer", "bogus"), fails(2, r"optimizer 'bogus' is not a known optimizer")),
    Case("cli", "fit: optimizer option unknown", lambda: cli(*FIT[:5], "--optimizer", "stlsq(speed=9)"), fails(2, r"STLSQ has no parameter 'speed'")),
    Case("cli", "fit: spline of order 9", lambda: cli("fit", "--data", RUN, "--differentiation", "spline(order=9)"), fails(2, r"order must be an integer >= 1 and <= 5")),
    Case("cli", "fit: negative --dt", lambda: cli("fit", "--data", DIR / "untimed.csv", "--dt", "-1"), fails(2, r"--dt must be a positive time step; got -1")),
    Case("cli", "fit: --dt NaN", lambda: cli("fit", "--data", DIR / "untimed.csv", "--dt", "nan"), fails(2, r"--dt must be a positive time step; got nan")),
    Case("cli", "fit: --dt beside a time column", lambda: cli(*FIT, "--dt", "0.01"), fails(2, r"--dt 0.01 was given but .*run.csv has a time column")),
    Case("cli", "fit: --dt a word", lambda: cli("fit", "--data", RUN, "--dt", "fast"), fails(2, r"argument --dt: invalid float value: 'fast'")),
    Case("cli", "fit: no --data", lambda: cli("fit"), fails(2, r"the following arguments are required: --data")),
    Case("cli", "fit: prior file missing", lambda: cli(*FIT, "--prior", out("none.py") + ":f"), fails(2, r"--prior file .*none.py does not exist")),
    Case("cli", "fit: prior file with a syntax error", lambda: cli(*FIT, "--prior", str(DIR / "broken.py") + ":f"), fails(1, r"--prior .*broken.py could not be imported: SyntaxError")),
    Case("cli", "fit: prior function missing", lambda: cli(*FIT, "--prior", PRIOR + ":g"), fails(2, r"--prior: .*prior.py has no function 'g'")),
    Case("cli", "fit: prior without a name", lambda: cli(*FIT, "--prior", PRIOR), fails(2, r"--prior must look like module.py:function")),
    Case("cli", "fit: prior of the wrong shape", lambda: cli(*FIT, "--prior", PRIOR + ":bad", "--out", out("m.json")), fails(1, r"prior must return an array of shape \(300, 2\)")),
    Case("cli", "fit: prior module not installed", lambda: cli(*FIT, "--prior", "no_such_module:f"), fails(1, r"--prior no_such_module could not be imported: ModuleNotFoundError")),
    Case("cli", "fit: out a folder", lambda: cli(*FIT, "--out", DIR / "folder"), fails(1, r"is a folder; give a file name")),
    Case("cli", "fit: out in a missing folder", lambda: cli(*FIT, "--out", DIR / "no" / "m.json"), fails(1, r"cannot write")),
    Case("cli", "fit: unknown state column", lambda: cli(*FIT, "--states", "x9"), fails(2, r"columns \['x9'\] not found")),
    Case("cli", "fit: works", lambda: cli(*FIT, "--prior", PRIOR + ":f", "--out", out("fitted.json")), returns(lambda r: r.code == 0 and "saved" in r.out and Path(out("fitted.json")).is_file())),
    Case("cli", "simulate: missing model", lambda: cli("simulate", "--model", out("none.json"), "--x0", "1,2", "--t", "0:1:0.1"), fails(1, r"model file '.*none.json' does not exist")),
    Case("cli", "simulate: model not JSON", lambda: cli("simulate", "--model", RUN, "--x0", "1,2", "--t", "0:1:0.1"), fails(1, r"model file: not valid JSON")),
    Case("cli", "simulate: x0 a word", lambda: cli("simulate", "--model", MODEL, "--x0", "abc", "--t", "0:1:0.1"), fails(2, r"--x0 must be comma-separated numbers; got 'abc'")),
    Case("cli", "simulate: x0 of 1 number", lambda: cli("simulate", "--model", MODEL, "--x0", "1", "--t", "0:1:0.1"), fails(1, r"x0 must be 2 numbers")),
    Case("cli", "simulate: x0 NaN", lambda: cli("simulate", "--model", MODEL, "--x0", "nan,1", "--t", "0:1:0.1"), fails(2, r"--x0 must be finite numbers")),
    Case("cli", "simulate: t without a step", lambda: cli("simulate", "--model", MODEL, "--x0", "1,2", "--t", "0:1"), fails(2, r"--t must be start:stop:step")),
    Case("cli", "simulate: t step 0", lambda: cli("simulate", "--model", MODEL, "--x0", "1,2", "--t", "0:1:0"), fails(2, r"need step > 0 and stop > start")),
    Case("cli", "simulate: t of 1e12 samples", lambda: cli("simulate", "--model", MODEL, "--x0", "1,2", "--t", "0:1e12:1"), fails(2, r"asks for 1e\+12 output samples")),
    Case("cli", "simulate: t backwards", lambda: cli("simulate", "--model", MODEL, "--x0", "1,2", "--t", "1:0:0.1"), fails(2, r"need step > 0 and stop > start")),
    Case("cli", "simulate: t words", lambda: cli("simulate", "--model", MODEL, "--x0", "1,2", "--t", "a,b"), fails(2, r"--t must be comma-separated numbers")),
    Case("cli", "simulate: t one time", lambda: cli("simulate", "--model", MODEL, "--x0", "1,2", "--t", "0"), fails(1, r"t must be a 1-D array of at least 2 output times")),
    Case("cli", "simulate: callable prior not given", lambda: cli("simulate", "--model", DIR / "callable.json", "--x0", "1,2", "--t", "0:1:0.1"), fails(2, r"--prior is required")),
    Case("cli", "simulate: a saved map iterates it", lambda: cli("simulate", "--model", str(DIR / "map.json"), "--x0=1", "--t", "0:2:1"), returns(lambda r: r.code == 0 and [float(v.split(",")[1]) for v in r.out.splitlines()[1:]] == [1.0, 0.9, 0.81])),
    Case("cli", "simulate: works", lambda: cli("simulate", "--model", MODEL, "--x0=0,1", "--t", "0:1:0.5"), returns(lambda r: r.code == 0 and r.out.splitlines()[0] == "t,x1,x2" and len(r.out.splitlines()) == 4)),
    Case("cli", "show: precision -1", lambda: cli("show", MODEL, "--precision", "-1"), fails(2, r"precision must be an integer >= 0")),
    Case("cli", "show: missing model", lambda: cli("show", out("none.json")), fails(1, r"does not exist")),
    Case("cli", "show: a CSV", lambda: cli("show", RUN), fails(1, r"model file: not valid JSON")),
    Case("cli", "show: a JSON list", lambda: cli("show", Path(out("list.json")).write_text("[]") and out("list.json")), fails(1, r"format is list")),
    Case("cli", "unknown command", lambda: cli("train"), fails(2, r"invalid choice: 'train'")),
    Case("cli", "no command", lambda: cli(), fails(2, r"the following arguments are required: command")),
    Case("cli", "--debug shows the exception", lambda: cli("--debug", "show", out("none.json")), raises(dc.errors.MissingFileError, r"does not exist")),
    Case("cli", "--debug on a bad spec", lambda: cli("--debug", *FIT, "--library", "poly("), raises(ParameterError, r"library spec")),
]


@params(CASES)
def test_case(case):
    check(case)


def test_help_says_that_prior_runs_the_file():
    run = cli("fit", "--help")
    assert run.code == 0 and "imports, i.e. runs" in " ".join(run.out.split())
