"""Every public callable has adversarial rows (see ``adversarial_reach.py``).

The callable a row exercises is recorded as the row runs (``adversarial.REACHED``); rows not
yet run in this process (this file alone, or another xdist worker ran them) are run here;
the isolated table's child process runs once per test run (``run_isolated_once``).
``pytest -s tests/test_adversarial_reach.py`` prints the rows per entry point.
"""
from __future__ import annotations

import collections

import pytest

import adversarial
from adversarial import check, check_isolated, run_isolated_once
from adversarial_reach import catalogue
from test_adversarial_count import TABLES


def _reach_all(tmp_path, tmp_path_factory, monkeypatch) -> dict[str, str | None]:
    monkeypatch.chdir(tmp_path)
    for table in TABLES:
        missing = [case for case in table.CASES if case.id not in adversarial.REACHED]
        if not missing:
            continue
        if hasattr(table, "prepare"):   # module globals its rows use, set by a fixture
            table.prepare()
        if hasattr(table, "PRELUDE"):   # rows run in a child process
            results = run_isolated_once(table.PRELUDE, missing, cwd=tmp_path,
                                        tmp_path_factory=tmp_path_factory)
            runs = [lambda case=case, results=results: check_isolated(case, results)
                    for case in missing]
        else:
            runs = [lambda case=case: check(case) for case in missing]
        for run in runs:
            try:
                run()
            except (AssertionError, pytest.fail.Exception):
                pass   # the row's own test reports it; here only its target counts
    return {case.id: adversarial.REACHED.get(case.id) for table in TABLES
            for case in table.CASES}


def test_every_public_callable_has_adversarial_rows(tmp_path, tmp_path_factory, monkeypatch):
    reached = _reach_all(tmp_path, tmp_path_factory, monkeypatch)
    counts = collections.Counter(name for name in reached.values() if name is not None)
    width = max(map(len, catalogue()))
    print(f"\n| {'entry point':{width}} | rows |\n|{'-' * (width + 2)}|------|")
    for name in sorted(catalogue()):
        print(f"| {name:{width}} | {counts[name]:4d} |")
    others = collections.Counter(case.entry for table in TABLES for case in table.CASES
                                 if reached[case.id] is None)
    for entry, n in sorted(others.items()):
        print(f"| {'(' + entry + ', no Python callable)':{width}} | {n:4d} |")
    print(f"| {'total':{width}} | {len(reached):4d} |")
    untraced = [case_id for case_id, name in reached.items()
                if name is None and not case_id.startswith("cli: ")]
    print("rows whose calls reach no public Python callable (besides the CLI's):", untraced)
    without = sorted(set(catalogue()) - set(counts))
    assert not without, f"{len(without)} public callables have no adversarial rows: {without}"
