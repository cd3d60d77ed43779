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
      --differentiation savitzky_golay --window 21 --threshold 0.05 --out model.json
  discrepancy simulate --model model.json --prior my_model.py:f_m --x0=-0.2,-0.3 --t 0:25:0.01 \\
      --out trajectory.csv
  discrepancy show model.json --latex
"""


def _load_callable(spec: str):
    """``file.py:name`` or ``package.module:name``: the user's own code, imported as code."""
    from .errors import ParameterError

    if ":" not in spec:
        raise ParameterError(f"--prior must look like module.py:function; got {spec!r}")
    module, name = spec.rsplit(":", 1)
    if module.endswith(".py"):
        path = Path(module)
        if not path.exists():
            raise FileNotFoundError(f"--prior file {module} does not exist")
        loader = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(loader)
        loader.loader.exec_module(mod)
    else:
        mod = importlib.import_module(module)
    if not hasattr(mod, name):
        raise ParameterError(f"--prior: {module} has no attribute {name!r}")
    return getattr(mod, name)


def _floats(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.split(",")])


def _times(text: str) -> np.ndarray:
    """``start:stop:step`` (stop included) or a comma list."""
    if ":" in text:
        start, stop, step = (float(v) for v in text.split(":"))
        return np.arange(start, stop + step / 2, step)
    return _floats(text)


def cmd_reproduce(args) -> int:
    """Run the chosen experiments; with ``all``, one that fails does not stop the others."""
    from .errors import DiscrepancyError
    from .experiments import EXPERIMENTS, get_experiment

    names = list(EXPERIMENTS) if args.name == "all" else [args.name]
    failed = []
    for name in names:
        print(f"[{name}] running ...", flush=True)
        try:
            folder = get_experiment(name)(args.out, quick=args.quick)
        except (DiscrepancyError, FileNotFoundError) as e:
            if len(names) == 1:
                raise
            print(f"[{name}] FAILED: {e}", file=sys.stderr, flush=True)
            failed.append(name)
            continue
        print(f"[{name}] wrote {folder}/report.md", flush=True)
    if failed:
        print(f"error: {len(failed)} of {len(names)} experiments failed: {', '.join(failed)}",
              file=sys.stderr)
        return 2
    return 0


def cmd_fit(args) -> None:
    from . import STLSQ, DiscrepancyModel
    from .differentiation import get_differentiation_method
    from .io import load
    from .libraries.spec import parse_library

    data = load(args.data, states=args.states.split(",") if args.states else None,
                inputs=args.inputs.split(",") if args.inputs else None)
    method_kw = {}
    if args.differentiation == "savitzky_golay":
        method_kw = dict(window_length=args.window, polyorder=args.polyorder)
    model = DiscrepancyModel(
        prior=_load_callable(args.prior) if args.prior else None,
        feature_library=parse_library(args.library),
        optimizer=STLSQ(threshold=args.threshold, alpha=args.alpha),
        differentiation_method=get_differentiation_method(args.differentiation, **method_kw),
        state_names=data.state_names, input_names=data.input_names or None)
    t = data.t if data.t is not None else args.dt
    model.fit(data.x, t=t, u=data.u)
    model.print()
    model.save(args.out)
    print(f"saved {args.out}")


def cmd_simulate(args) -> None:
    from . import load_model

    model = load_model(args.model, prior=_load_callable(args.prior) if args.prior else None)
    t = _times(args.t)
    x = model.simulate(_floats(args.x0), t)
    table = np.column_stack([t, x])
    header = ",".join(["t", *model.state_names_])
    if args.out:
        np.savetxt(args.out, table, delimiter=",", header=header, comments="")
        print(f"wrote {len(t)} samples to {args.out}")
    else:
        np.savetxt(sys.stdout, table, delimiter=",", header=header, comments="", fmt="%.8g")


def cmd_show(args) -> None:
    from .models.model_file import read_model_file

    fields = read_model_file(args.model)
    from . import load_model

    prior = fields["prior"]
    model = load_model(args.model, prior=(lambda x, u=None: np.zeros_like(x))
                       if prior and prior["kind"] == "callable" else None)
    kind = "none (plain SINDy)" if prior is None else prior["kind"]
    print(f"states {model.state_names_}, inputs {model.input_names_}, prior: {kind}")
    model.print(precision=args.precision)
    if args.latex:
        part = "discrepancy" if prior and prior["kind"] == "callable" else None
        print(model.to_latex(precision=args.precision, part=part))


def build_parser() -> argparse.ArgumentParser:
    from .experiments import EXPERIMENTS

    p = argparse.ArgumentParser(prog="discrepancy", epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                description="Learn sparse discrepancy models f_m + g with SINDy.")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("reproduce", help="run a paper example; writes DIR/NAME/report.md")
    r.add_argument("name", choices=[*EXPERIMENTS, "all"])
    r.add_argument("--out", default="out", help="output folder (default: out)")
    r.add_argument("--quick", action="store_true", help="fewer seeds/cases (for smoke tests)")
    r.set_defaults(func=cmd_reproduce)
    f = sub.add_parser("fit", help="fit a model to a data file and save it as JSON")
    f.add_argument("--data", required=True, help="CSV (header row), NPZ, MAT or HDF5 file")
    f.add_argument("--prior", help="module.py:function with f_m(x, u) -> (m, n); none = SINDy")
    f.add_argument("--library", default="poly(2)", help='e.g. "poly(3)+fourier(1)"')
    f.add_argument("--states", help="comma-separated state columns/variables")
    f.add_argument("--inputs", help="comma-separated input columns/variables")
    f.add_argument("--dt", type=float, default=None, help="time step if the file has no t")
    f.add_argument("--threshold", type=float, default=0.05)
    f.add_argument("--alpha", type=float, default=0.05, help="ridge weight of STLSQ")
    f.add_argument("--differentiation", default="savitzky_golay")
    f.add_argument("--window", type=int, default=21, help="Savitzky-Golay window (odd)")
    f.add_argument("--polyorder", type=int, default=3)
    f.add_argument("--out", default="model.json")
    f.set_defaults(func=cmd_fit)
    s = sub.add_parser("simulate", help="simulate a saved model")
    s.add_argument("--model", required=True)
    s.add_argument("--prior", help="module.py:function, if the model was fitted with one")
    s.add_argument("--x0", required=True,
                   help="comma-separated initial state; write --x0=-0.2,-0.3 "
                   "when it starts with a minus")
    s.add_argument("--t", required=True, help="start:stop:step or comma-separated times")
    s.add_argument("--out", help="CSV file (default: print)")
    s.set_defaults(func=cmd_simulate)
    w = sub.add_parser("show", help="print a saved model's equations")
    w.add_argument("model")
    w.add_argument("--latex", action="store_true")
    w.add_argument("--precision", type=int, default=4)
    w.set_defaults(func=cmd_show)
    return p


def main(argv=None) -> int:
    from .errors import DiscrepancyError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args) or 0
    except (DiscrepancyError, FileNotFoundError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
