"""``reproduce``: a subcommand the library's command line finds through the
``discrepancy.commands`` entry point (the library never imports this package)."""
from __future__ import annotations

import argparse
import inspect
import sys

from .experiments import EXPERIMENTS, get_experiment


def add_reproduce(subparsers) -> None:
    """Add ``reproduce NAME --out DIR [--quick]`` to an argparse subparsers object."""
    r = subparsers.add_parser("reproduce", help="run a paper example or benchmark; writes "
                              "DIR/NAME/report.md, its figures and results.json")
    r.add_argument("name", choices=[*EXPERIMENTS, "all"])
    r.add_argument("--out", default="out", help="output folder (default: out)")
    r.add_argument("--quick", action="store_true", help="fewer seeds/cases (for smoke tests)")
    r.add_argument("--full", action="store_true", help="the whole study where an experiment "
                   "runs a smaller one by default (cart-leaderboard: the full grid)")
    r.set_defaults(func=reproduce)


def reproduce(args) -> int:
    """Run the chosen experiments; with ``all``, one that fails does not stop the others."""
    from discrepancy.errors import DiscrepancyError

    names = list(EXPERIMENTS) if args.name == "all" else [args.name]
    failed = []
    for name in names:
        print(f"[{name}] running ...", flush=True)
        run = get_experiment(name)
        options = {"quick": args.quick}
        if getattr(args, "full", False) and "full" in inspect.signature(run).parameters:
            options["full"] = True
        try:
            folder = run(args.out, **options)
        except (DiscrepancyError, OSError) as e:
            if len(names) == 1:
                raise
            print(f"[{name}] FAILED: {e}", file=sys.stderr, flush=True)
            failed.append(name)
            continue
        print(f"[{name}] wrote {folder}/report.md", flush=True)
    if failed:
        print(f"error: {len(failed)} of {len(names)} experiments failed: {', '.join(failed)}",
              file=sys.stderr)
        return 1
    return 0


def main(argv=None) -> int:
    """``python -m discrepancy_paper reproduce ...``."""
    parser = argparse.ArgumentParser(prog="python -m discrepancy_paper")
    add_reproduce(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)
