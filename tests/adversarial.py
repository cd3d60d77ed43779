"""The adversarial suite's machinery: one table row per bad or edge input.

A row is ``Case(entry, name, call, expect)``: ``call`` is a function of nothing (in-process
rows) or a line of code (isolated rows), ``expect`` is :func:`raises` (an exception class
that must also be a :class:`~discrepancy.errors.DiscrepancyError`, and a regex its message
must match, naming the argument) or :func:`returns` (a check of the correct answer).

Rows that could hang or allocate run in one child process per table, under a memory cap
(``RLIMIT_AS``) and a time limit per row (:func:`run_isolated`), so the suite stays fast
and a failure is reported, not suffered. The tables live in ``test_adversarial_*.py``;
``test_adversarial_count.py`` checks that together they hold as many distinct rows per
entry point as its docstring says.
"""
from __future__ import annotations

import fcntl
import hashlib
import json
import os
import re
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from adversarial_reach import CHILD_HOOK, target, watch
from discrepancy.errors import DiscrepancyError

#: case id -> the public callable the row exercised (``adversarial_reach.target``), filled
#: as rows run; ``test_adversarial_reach.py`` checks that every public callable has rows
REACHED: dict[str, str | None] = {}


def circle(m: int):
    """``(t, x, x_dot)`` of ``m`` samples of ``x1' = x2, x2' = -x1`` (step 0.01), exact."""
    t = np.arange(m) * 0.01
    x = np.c_[np.sin(t), np.cos(t)]
    return t, x, np.c_[x[:, 1], -x[:, 0]]


def fast(**kw):
    """A model with a fast fit set-up (finite differences, threshold 0.05) and ``kw``."""
    import discrepancy as dc

    return dc.DiscrepancyModel(**{"differentiation_method": "finite_difference",
                                  "optimizer": dc.STLSQ(threshold=0.05), **kw})


#: memory cap (bytes of address space) and time limit (s of the child's CPU time; four times
#: that of wall time catches a row that waits forever) of an isolated row
MEMORY_CAP = 3 * 2**30
ROW_SECONDS = 20


@dataclass(frozen=True)
class Expect:
    error: type | None
    pattern: str | None
    check: Any = None


def raises(error: type, pattern: str) -> Expect:
    """The call must raise ``error`` (a DiscrepancyError subclass) matching ``pattern``."""
    assert issubclass(error, DiscrepancyError), error
    return Expect(error, pattern)


def returns(check) -> Expect:
    """The call must return a value for which ``check(value)`` is true (the right answer)."""
    return Expect(None, None, check)


@dataclass(frozen=True)
class Case:
    entry: str
    name: str
    call: Any
    expect: Expect

    @property
    def id(self) -> str:
        return f"{self.entry}: {self.name}"


def params(cases: list[Case]):
    """``pytest.mark.parametrize`` arguments for a table (ids are the rows' names)."""
    ids = [c.id for c in cases]
    assert len(set(ids)) == len(ids), [i for i in ids if ids.count(i) > 1]
    return pytest.mark.parametrize("case", cases, ids=ids)


def check(case: Case) -> None:
    """Run an in-process row and assert its expectation; record the callable it exercised."""
    calls: list = []
    try:
        if case.expect.error is None:
            with watch(calls):
                value = case.call()
            assert case.expect.check(value), f"{case.id}: wrong answer {value!r:.300}"
            return
        with pytest.raises(Exception) as info, watch(calls):  # noqa: B017  (inspected below)
            case.call()
        assert_error(case, type(info.value), str(info.value))
    finally:
        REACHED[case.id] = target(calls)


def assert_error(case: Case, kind: type | str, message: str) -> None:
    names = [k.__name__ for k in kind.__mro__] if isinstance(kind, type) else kind.split(",")
    expected = case.expect.error
    assert expected is not None, f"{case.id}: raised {names[0]}: {message}"
    assert "DiscrepancyError" in names and expected.__name__ in names, \
        f"{case.id}: expected {expected.__name__}, got {names[0]}: {message}"
    assert re.search(case.expect.pattern, message, re.S), \
        f"{case.id}: message {message!r} does not match {case.expect.pattern!r}"


_CHILD = '''
import json, resource, signal, sys, time, traceback
resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
class _Late(BaseException):
    pass
def _alarm(*_):
    raise _Late()
signal.signal(signal.SIGALRM, _alarm)
signal.signal(signal.SIGPROF, _alarm)
{hook}
{prelude}
_rows = json.loads(sys.stdin.read())
for _i, _code in enumerate(_rows):
    _start = time.process_time()
    _calls.clear()
    signal.setitimer(signal.ITIMER_PROF, {seconds})
    signal.alarm(4 * {seconds})
    try:
        sys.settrace(_hook)
        try:
            _value = eval(compile(_code, f"row {{_i}}", "eval"))
        finally:
            sys.settrace(None)
        _out = {{"kind": None, "value": repr(_value)[:300]}}
    except _Late:
        _out = {{"kind": "Timeout", "message": "no answer in {seconds} s of CPU time"}}
    except BaseException as _e:
        _out = {{"kind": ",".join(k.__name__ for k in type(_e).__mro__), "message": str(_e),
                "where": traceback.format_exc()[-600:]}}
    finally:
        signal.alarm(0)
        signal.setitimer(signal.ITIMER_PROF, 0)
    _out["seconds"] = time.process_time() - _start
    _out["calls"] = _calls
    print(json.dumps(_out), flush=True)
'''


def run_isolated(prelude: str, cases: list[Case], *, cwd) -> dict[str, dict]:
    """Run the rows' code (expressions) in one child process, capped; results by case id.

    A row's result is ``{"kind": "Class,Base,...", "message"}`` for an exception,
    ``{"kind": None, "value"}`` for a value, or ``{"kind": "Timeout"}``; rows the child
    never reached (it died) are missing."""
    script = _CHILD.format(cap=MEMORY_CAP, seconds=ROW_SECONDS, hook=CHILD_HOOK,
                           prelude=textwrap.dedent(prelude))
    proc = subprocess.run([sys.executable, "-c", script], input=json.dumps(
        [c.call for c in cases]), capture_output=True, text=True, cwd=cwd,
        timeout=60 + ROW_SECONDS * len(cases))
    lines = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    results = {c.id: r for c, r in zip(cases, lines, strict=False)}
    if len(lines) < len(cases):
        results["__died__"] = {"stderr": proc.stderr[-2000:]}
    return results


_RESULTS: dict[str, dict] = {}


def run_isolated_once(prelude: str, cases: list[Case], *, cwd, tmp_path_factory) -> dict:
    """:func:`run_isolated` once per test run for the same rows: kept in this process and,
    under pytest-xdist, shared by the workers through a file in the run's common temporary
    directory (the first worker to ask runs the child while holding a lock, another waits
    and reads), so the isolated table and the reach test do not both pay for the child."""
    key = hashlib.sha256(json.dumps([prelude, [c.call for c in cases]]).encode()).hexdigest()
    if key not in _RESULTS:
        if os.environ.get("PYTEST_XDIST_WORKER"):
            shared = tmp_path_factory.getbasetemp().parent / f"isolated-{key[:16]}.json"
            with open(shared.with_suffix(".lock"), "w") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX)
                if not shared.exists():
                    shared.write_text(json.dumps(run_isolated(prelude, cases, cwd=cwd)))
                _RESULTS[key] = json.loads(shared.read_text())
        else:
            _RESULTS[key] = run_isolated(prelude, cases, cwd=cwd)
    return _RESULTS[key]


def check_isolated(case: Case, results: dict) -> None:
    """Assert an isolated row's result (from :func:`run_isolated`)."""
    result = results.get(case.id)
    REACHED[case.id] = target((result or {}).get("calls", []))
    assert result is not None, f"{case.id}: the child process died: {results.get('__died__')}"
    assert result["kind"] != "Timeout", f"{case.id}: hangs ({result['message']})"
    if case.expect.error is None:
        assert result["kind"] is None, f"{case.id}: raised {result}"
        assert case.expect.check(result["value"]), f"{case.id}: wrong answer {result['value']}"
        return
    assert result["kind"] is not None, f"{case.id}: returned {result['value']}"
    assert_error(case, result["kind"], result["message"])
    assert result["seconds"] < ROW_SECONDS / 2, f"{case.id}: took {result['seconds']:.1f} s of CPU"
