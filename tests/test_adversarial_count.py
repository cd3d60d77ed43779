"""The adversarial suite tries 1120 distinct bad or edge inputs over every public entry point.

| entry point | rows |
|---|---|
| cli | 46 |
| library | 58 |
| optimizer | 84 |
| differentiation | 44 |
| energy | 123 |
| control | 114 |
| estimation | 57 |
| model file | 54 |
| io.load | 40 |
| stream | 40 |
| dask | 11 |
| fit | 79 |
| prior | 21 |
| model | 78 |
| isolated | 51 |
| predict | 17 |
| score | 21 |
| export | 21 |
| simulate | 54 |
| bootstrap | 21 |
| metrics | 9 |
| symbolic | 15 |
| data | 5 |
| selection | 6 |
| systems | 8 |
| pde | 33 |
| plots | 10 |
| total | 1120 |

899 rows must raise a DiscrepancyError subclass (also the matching builtin) whose message
matches a pattern naming the argument; 221 must give the right answer, checked against an
exact value (closed forms, numpy least squares, the in-memory fit). The 51 isolated rows
(resource limits, would-be hangs, the real command line) run in one child process under a
3 GiB address-space cap and 20 s per row. This file checks that the tables hold exactly
these numbers of distinct rows, so the figures cannot drift from the suite; which public
callable each row exercises, and that every one has rows, is ``test_adversarial_reach.py``'s.
"""
from __future__ import annotations

import collections
import re
from pathlib import Path

import test_adversarial_cli
import test_adversarial_components
import test_adversarial_energy_control
import test_adversarial_estimation
import test_adversarial_files
import test_adversarial_fit
import test_adversarial_isolated
import test_adversarial_models
import test_adversarial_options
import test_adversarial_public

TABLES = [test_adversarial_fit, test_adversarial_components, test_adversarial_models,
          test_adversarial_files, test_adversarial_cli, test_adversarial_energy_control,
          test_adversarial_isolated, test_adversarial_estimation, test_adversarial_options,
          test_adversarial_public]


def test_the_docstring_gives_the_number_of_distinct_rows_per_entry_point():
    cases = [case for table in TABLES for case in table.CASES]
    ids = [case.id for case in cases]
    assert len(set(ids)) == len(ids) >= 400
    declared = dict(re.findall(r"^\| ([a-z. ]+) \| (\d+) \|$", __doc__, re.M))
    counts = collections.Counter(case.entry for case in cases)
    assert {k: int(v) for k, v in declared.items() if k != "total"} == dict(counts)
    assert int(declared["total"]) == len(cases)
    errors = sum(case.expect.error is not None for case in cases)
    assert f"{errors} rows must raise" in " ".join(__doc__.split())
    assert f"{len(cases) - errors} must give the right answer" in " ".join(__doc__.split())
    assert f"The {counts['isolated']} isolated rows" in " ".join(__doc__.split())


def test_the_readme_and_the_errors_page_give_the_same_count():
    root = Path(__file__).resolve().parents[1]
    total = sum(len(table.CASES) for table in TABLES)
    for page in (root / "README.md", root / "docs" / "guide" / "errors.md"):
        text = " ".join(page.read_text().split())
        assert f"tries {total} distinct bad or edge inputs" in text, page.name
