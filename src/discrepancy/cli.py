"""Command line: ``discrepancy reproduce | fit | simulate | show``. Thin: parse, call, print."""
from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
from pathlib import Path

import numpy as np

EPILOG = """examples:
  discrepancy reproduce all --out out/
  discrepancy reproduce vdp-parameter --out out/
  discrepancy fit --data run.csv --prior my_model.py:f_m --library "poly(3)+fourier(1)" \\
      --differentiation "savitzky_golay(window_length=21)" --optimizer "stlsq(threshold=0.05)" \\
      --out model.json
  discrepancy simulate --model model.json --prior my_model.py:f_m --x0=-0.2,-0.3 --t 0:25:0.01 \\
      --out trajectory.csv
  discrepancy simulate --model forced.json --x0=0,0 --inputs run.csv --method rk4 \\
      --u-hold bandlimited                # inputs (and times) from a file
  discrepancy show model.json --latex

--prior FILE.py:NAME imports (runs) FILE.py as Python code to get the function NAME: only
name files you wrote or trust. Model files are JSON and are never run.
Errors print one line on stderr and exit with 2 (bad arguments) or 1 (failure); --debug
shows the traceback.
"""


def _load_callable(spec: str):
    """``file.py:name`` or ``package.module:name``: the user's own code, imported as code."""
    from .errors import ParameterError, PriorError

    if ":" not in spec:
        raise ParameterError(f"--prior must look like module.py:function; got {spec!r}")
    module, name = spec.rsplit(":", 1)
    try:
        if module.endswith(".py"):
            path = Path(module)
            if not path.is_file():
                raise ParameterError(f"--prior file {module} does not exist")
            loader = importlib.util.spec_from_file_location(path.stem, path)
            mod = importlib.util.module_from_spec(loader)
            loader.loader.exec_module(mod)
        else:
            mod = importlib.import_module(module)
    except ParameterError:
        raise
    except Exception as e:  # the user's file failed to import: say which and why
        raise PriorError(f"--prior {module} could not be imported: {type(e).__name__}: "
                         f"{e}") from e
    f = getattr(mod, name, None)
    if not callable(f):
        raise ParameterError(f"--prior: {module} has no function {name!r}")
    return f


MAX_TIMES = 10_000_000   # output samples a command-line simulation may ask for


def _floats(option: str, text: str) -> np.ndarray:
    from .errors import ParameterError

    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ParameterError(f"{option} must be comma-separated numbers; got {text!r}") from None
    if not np.all(np.isfinite(values)):
        raise ParameterError(f"{option} must be finite numbers; got {text!r}")
    return values


def _times(text: str) -> np.ndarray:
    """``start:stop:step`` (stop included) or a comma list, checked before allocating."""
    from .errors import ParameterError

    if ":" not in text:
        return _floats("--t", text)
    parts = text.split(":")
    if len(parts) != 3:
        raise ParameterError(f"--t must be start:stop:step or comma-separated times; got {text!r}")
    start, stop, step = _floats("--t", ",".join(parts))
    if step <= 0 or stop <= start:
        raise ParameterError(f"--t {text!r}: need step > 0 and stop > start")
    count = (stop - start) / step + 1
    if count > MAX_TIMES:
        raise ParameterError(f"--t {text!r} asks for {count:.3g} output samples; at most "
                             f"{MAX_TIMES:.0e} (use a larger step)")
    return start + step * np.arange(int(np.floor(count + 1e-9)))


def add_plugin_commands(sub) -> set[str]:
    """Subcommands of other installed packages (entry point group ``discrepancy.commands``:
    a function adding parsers to argparse subparsers), e.g. the paper package's
    ``reproduce``. Returns the names added; the library itself imports none of them."""
    from importlib.metadata import entry_points

    before = set(sub.choices)
    for entry in entry_points(group="discrepancy.commands"):
        entry.load()(sub)
    return set(sub.choices) - before


def _no_paper_package(args) -> int:
    print("error: 'reproduce' runs the paper's examples, which are in the separate package "
          "discrepancy-paper; from a clone of the repository: pip install -e paper",
          file=sys.stderr)
    return 2


def cmd_fit(args) -> None:
    """``discrepancy fit``: load a data file, fit a model and save it as JSON."""
    from . import DiscrepancyModel
    from .errors import ParameterError
    from .io import load

    data = load(args.data, states=args.states.split(",") if args.states else None,
                inputs=args.inputs.split(",") if args.inputs else None)
    model = DiscrepancyModel(
        prior=_load_callable(args.prior) if args.prior else None,
        feature_library=args.library, optimizer=args.optimizer,
        differentiation_method=args.differentiation,
        state_names=data.state_names, input_names=data.input_names or None,
        selection=args.selection)
    if args.dt is not None and (not np.isfinite(args.dt) or args.dt <= 0):
        raise ParameterError(f"--dt must be a positive time step; got {args.dt}")
    if args.dt is not None and data.t is not None:
        raise ParameterError(f"--dt {args.dt} was given but {args.data} has a time column "
                             "'t'; give one or the other")
    t = data.t if data.t is not None else args.dt
    model.fit(data.x, t=t, u=data.u)
    model.print()
    model.save(args.out)
    print(f"saved {args.out}")


def _placeholder_prior(x, u=None):
    return np.zeros_like(x)


def _stored(path):
    """A model file's content and whether its prior is a callable (not stored)."""
    from .models.files.model_file import read_json

    doc = read_json(path)
    prior = doc.get("prior") if isinstance(doc, dict) else None
    return doc, isinstance(prior, dict) and prior.get("kind") == "callable"


def cmd_simulate(args) -> None:
    """``discrepancy simulate``: simulate a saved model from ``--x0`` (with recorded ``--inputs``)
    and print or write the trajectory."""
    from . import DiscrepancyModel

    doc, needs_prior = _stored(args.model)
    if needs_prior and not args.prior:
        from .errors import ParameterError
        raise ParameterError("--prior is required: the model was fitted with a Python prior, "
                             "which model files never store as code")
    model = DiscrepancyModel.from_state(
        doc, prior=_load_callable(args.prior) if args.prior else None)
    t, u = _simulation_inputs(args, model)
    # a map iterates once per row of --t (its values label the rows); RK4 options are for ODEs
    options = {} if model.discrete_time else {"u_hold": args.u_hold, "substeps": args.substeps}
    if args.method:
        options["method"] = args.method
    x = model.simulate(_floats("--x0", args.x0), t, u=u, **options)
    table = np.column_stack([t, x])
    header = ",".join(["t", *model.state_names_])
    if args.out:
        np.savetxt(args.out, table, delimiter=",", header=header, comments="")
        print(f"wrote {len(t)} samples to {args.out}")
    else:
        np.savetxt(sys.stdout, table, delimiter=",", header=header, comments="", fmt="%.8g")


def _simulation_inputs(args, model):
    """Times and input samples: inputs from ``--inputs`` (its time column, or ``--t``)."""
    from .errors import ParameterError, ShapeError
    from .io import load

    if not args.inputs:
        if model.n_inputs_:
            raise ParameterError(f"--inputs is required: the model has inputs "
                                 f"{model.input_names_}; give a file of their samples")
        if args.t is None:
            raise ParameterError("--t is required (start:stop:step or comma-separated times)")
        return _times(args.t), None
    if not model.n_inputs_:
        raise ParameterError("--inputs was given but the model has no inputs")
    columns = args.input_columns.split(",") if args.input_columns else model.input_names_
    data = load(args.inputs, states=columns, time="t")
    t = _times(args.t) if args.t is not None else data.t
    if t is None:
        raise ParameterError(f"{args.inputs} has no time column 't'; give --t")
    if len(t) != len(data.x):
        raise ShapeError(f"--t has {len(t)} times but {args.inputs} has {len(data.x)} input "
                         "samples; they must match")
    return t, data.x


def cmd_show(args) -> None:
    """``discrepancy show``: print a saved model's equations (``--latex``: as LaTeX)."""
    from . import DiscrepancyModel

    doc, callable_prior = _stored(args.model)
    declared = doc.get("user_functions", []) if isinstance(doc, dict) else []
    functions = {name: _placeholder_prior for name in declared
                 if isinstance(name, str)}  # names only: show evaluates nothing
    model = DiscrepancyModel.from_state(doc, prior=_placeholder_prior if callable_prior
                                        else None, functions=functions)
    kind = "none (plain SINDy)" if model.prior is None else \
        "Python callable" if callable_prior else "sympy"
    print(f"states {model.state_names_}, inputs {model.input_names_}, prior: {kind}")
    model.print(precision=args.precision)
    if args.latex:
        part = "discrepancy" if callable_prior else None
        print(model.to_latex(precision=max(args.precision, 1), part=part))


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors on one line (exit code 2), like every other error."""

    def error(self, message):
        self.exit(2, f"error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``discrepancy`` command's argument parser: ``fit``, ``simulate``, ``show`` and the
    commands of installed plug-ins (``reproduce``)."""
    p = _Parser(prog="discrepancy", epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                description="Learn sparse discrepancy models f_m + g with SINDy.")
    sub = p.add_subparsers(dest="command", required=True)
    if "reproduce" not in add_plugin_commands(sub):
        r = sub.add_parser("reproduce", help="run a paper example (needs the discrepancy-paper "
                           "package)")
        r.add_argument("rest", nargs=argparse.REMAINDER)
        r.set_defaults(func=_no_paper_package)
    f = sub.add_parser("fit", help="fit a model to a data file and save it as JSON")
    f.add_argument("--data", required=True, help="CSV (header row), NPZ, MAT or HDF5 file")
    f.add_argument("--prior", help="FILE.py:NAME (imports, i.e. runs, FILE.py) or module:NAME "
                   "with f_m(x, u) -> (m, n); none = plain SINDy")
    f.add_argument("--library", default="poly(2)", help='e.g. "poly(3)+fourier(1)"')
    f.add_argument("--states", help="comma-separated state columns/variables")
    f.add_argument("--inputs", help="comma-separated input columns/variables")
    f.add_argument("--dt", type=float, default=None, help="time step if the file has no t")
    f.add_argument("--optimizer", default=None,
                   help='e.g. "stlsq(threshold=0.05)" or "lasso(alpha=1e-3)" (default: the '
                   'library\'s, STLSQ with an automatic threshold)')
    f.add_argument("--differentiation", default=None,
                   help='e.g. "savitzky_golay(window_length=31, polyorder=3)" or "spline(s=0.01)" '
                   "(default: the library's)")
    f.add_argument("--selection", default="auto", choices=["auto", "forecast", "optimizer"],
                   help="how terms are chosen: auto (default: by forecasts, the prior alone "
                   "included, when the optimizer chooses its own sparsity), forecast, or "
                   "optimizer (its own equation-error choice)")
    f.add_argument("--out", default="model.json")
    f.set_defaults(func=cmd_fit)
    s = sub.add_parser("simulate", help="simulate a saved model")
    s.add_argument("--model", required=True)
    s.add_argument("--prior", help="FILE.py:NAME (imports, i.e. runs, FILE.py), if the model "
                   "was fitted with a Python prior")
    s.add_argument("--x0", required=True,
                   help="comma-separated initial state; write --x0=-0.2,-0.3 "
                   "when it starts with a minus")
    s.add_argument("--t", help="start:stop:step or comma-separated times (default: the "
                   "time column of --inputs)")
    s.add_argument("--inputs", help="file (CSV, NPZ, MAT, HDF5) of input samples, one column "
                   "per input (named like the model's inputs), with a time column t or --t")
    s.add_argument("--input-columns", help="comma-separated input column names in --inputs "
                   "(default: the model's input names)")
    s.add_argument("--u-hold", default="linear", choices=["linear", "zoh", "bandlimited"],
                   help="the input between samples (default linear)")
    s.add_argument("--method", help="LSODA (default) or another scipy method, or rk4 "
                   "(fixed steps, compiled: fast for long records with measured inputs)")
    s.add_argument("--substeps", type=int, default=4, help="rk4 steps per sample (default 4)")
    s.add_argument("--out", help="CSV file (default: print)")
    s.set_defaults(func=cmd_simulate)
    w = sub.add_parser("show", help="print a saved model's equations")
    w.add_argument("model")
    w.add_argument("--latex", action="store_true")
    w.add_argument("--precision", type=int, default=4)
    w.set_defaults(func=cmd_show)
    return p


def main(argv=None) -> int:
    """Run the command line; returns the exit code (0 success, 1 failure, 2 bad arguments)."""
    from .errors import DiscrepancyError, ParameterError

    argv = sys.argv[1:] if argv is None else list(argv)
    debug = "--debug" in argv  # anywhere on the line, for every subcommand
    args = build_parser().parse_args([a for a in argv if a != "--debug"])
    try:
        return args.func(args) or 0
    except (DiscrepancyError, OSError) as e:
        if debug:
            raise
        print(f"error: {_one_line(e)}", file=sys.stderr)
        return 2 if isinstance(e, ParameterError) else 1
    except Exception as e:  # a bug, or an error raised by the user's --prior code
        if debug:
            raise
        print(f"error: {type(e).__name__}: {_one_line(e)} (rerun with --debug for the "
              "traceback)", file=sys.stderr)
        return 1


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


if __name__ == "__main__":
    sys.exit(main())
