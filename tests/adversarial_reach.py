"""Which public callable an adversarial row exercises, derived by watching the row run.

The *catalogue* is every public callable: the names in the ``__all__`` of ``discrepancy``
and of its public subpackages (for a module without ``__all__``, the classes and functions
it defines, the rule of ``docs/_ext/api_catalogue.py``), and the public methods of the
estimators and controllers users call methods on (:data:`METHODS_OF`).

A row's *target* is the last catalogued callable that the tests' own code called while the
row ran: the one that raised, or whose answer the row checks. It is recorded from a
trace hook (:func:`watch`), so it cannot drift from what the row really does; rows run in
a child process report the same record back (:data:`CHILD_HOOK`). The hook is a global
``sys.settrace`` function that asks for no line events: it is called once as each Python
frame starts and never on returns or C calls, so rows run at nearly full speed (a
``sys.setprofile`` hook, which sees those too, made the costliest isolated row 60 % slower).
"""
from __future__ import annotations

import dataclasses
import importlib
import inspect
import os
import sys
from contextlib import contextmanager

#: modules whose public names are entry points (``discrepancy`` itself and its subpackages)
MODULES = ("discrepancy", "control", "systems", "energy", "estimation", "pde", "selection",
           "data", "libraries", "optimizers", "differentiation", "plots", "metrics", "io",
           "symbolic")
#: classes whose public methods are entry points of their own (``Class.method``)
METHODS_OF = ("DiscrepancyModel", "PDEDiscrepancyModel", "EnergyDiscrepancy",
              "DissipationDiscrepancy", "MPC")
TESTS = os.path.dirname(os.path.abspath(__file__))


def is_record(value) -> bool:
    """A data record the library returns (a dataclass with no public method and no checks of
    its own, ``__post_init__``): users read its fields; its producer is the entry point."""
    return inspect.isclass(value) and dataclasses.is_dataclass(value) \
        and not hasattr(value, "__post_init__") \
        and not any(not name.startswith("_") and callable(member)
                    for name, member in inspect.getmembers(value)
                    if inspect.isfunction(member) or inspect.ismethod(member))


def _public_names(module) -> list[str]:
    if hasattr(module, "__all__"):
        return list(module.__all__)
    return [name for name, value in vars(module).items() if not name.startswith("_")
            and (inspect.isclass(value) or inspect.isfunction(value))
            and value.__module__ == module.__name__]


def _modules():
    for short in MODULES:
        name = "discrepancy" if short == "discrepancy" else f"discrepancy.{short}"
        module = importlib.import_module(name)
        if short == "plots":   # a package of figure modules: each one's functions
            for sub in ("selection", "trajectories", "uncertainty"):
                yield f"plots.{sub}", importlib.import_module(f"{name}.{sub}")
        else:
            yield ("" if short == "discrepancy" else short), module


def catalogue() -> dict[str, object]:
    """Public name (``"MPC"``, ``"control.closed_loop"``, ``"DiscrepancyModel.fit"``) ->
    the object; one name per object, the shortest path (``discrepancy.X`` first). Records
    (:func:`is_record`) are left out: they are returned, not called."""
    found: dict[str, object] = {}
    seen: set[int] = set()
    for prefix, module in _modules():
        for name in _public_names(module):
            value = getattr(module, name)
            if inspect.ismodule(value) or not callable(value) or id(value) in seen:
                continue
            if inspect.isclass(value) and (issubclass(value, (Warning, Exception))
                                           or inspect.isabstract(value) or is_record(value)):
                continue   # raised or warned by the library, abstract, or data: not called
            seen.add(id(value))
            found[f"{prefix}.{name}" if prefix else name] = value
    for cls_name, cls in list(found.items()):
        if cls_name.split(".")[-1] in METHODS_OF:
            for name, value in inspect.getmembers(cls):
                function = getattr(value, "__func__", value)
                if not name.startswith("_") and inspect.isfunction(function) \
                        and function.__module__.startswith("discrepancy"):
                    found[f"{cls_name}.{name}"] = value
    return found


def _code_key(code) -> tuple[str, str]:
    return code.co_filename, code.co_qualname


def _index(found: dict[str, object]) -> tuple[dict, dict]:
    """(code key of a plain function -> name, class name -> catalogue prefix of the class)."""
    functions, classes = {}, {}
    for name, value in found.items():
        if inspect.isclass(value):
            classes[f"{value.__module__}.{value.__qualname__}"] = name
        elif inspect.isfunction(value) and "." not in value.__qualname__:
            functions[_code_key(value.__code__)] = name
    return functions, classes


def _record(frame) -> tuple[str, str, str | None]:
    """(file, qualname, class of self/cls or None) of the call that opened ``frame``."""
    code = frame.f_code
    owner = None
    if code.co_argcount and code.co_varnames[0] in ("self", "cls"):
        bound = frame.f_locals.get(code.co_varnames[0])
        kind = bound if isinstance(bound, type) else type(bound)
        owner = f"{kind.__module__}.{kind.__qualname__}"
    return code.co_filename, code.co_qualname, owner


def _call_record(frame) -> tuple[str, str, str | None] | None:
    """The :func:`_record` of a call test code made to the library, or None."""
    caller = frame.f_back
    if caller is None or not caller.f_code.co_filename.startswith(TESTS) \
            or frame.f_code.co_filename.startswith(TESTS):
        return None
    return _record(frame)


def name_of(record, found, found_index) -> str | None:
    """The catalogue name of a call record, or None if the call is not an entry point."""
    functions, classes = found_index
    filename, qualname, owner = record
    if owner is None:
        return functions.get((filename, qualname))
    if owner not in classes:
        return None
    cls, method = classes[owner], qualname.rsplit(".", 1)[-1]
    if method == "__init__" or cls.split(".")[-1] not in METHODS_OF:
        return cls   # the class is the entry point; its methods are part of it
    return f"{cls}.{method}" if f"{cls}.{method}" in found else None


@contextmanager
def watch(records: list):
    """Append the call record of every call test code makes to the library, in order."""
    def hook(frame, event, _arg):
        if event == "call":
            record = _call_record(frame)
            if record is not None:
                records.append(record)
        # None: no line, return or exception events in this frame

    previous = sys.gettrace()
    sys.settrace(hook)
    try:
        yield records
    finally:
        sys.settrace(previous)


#: the same hook for a child process (``adversarial.run_isolated``): records the calls the
#: row's own code (``row N``) and the child's prelude (``<string>``) make, in ``_calls``
CHILD_HOOK = inspect.getsource(_record) + '''
_calls = []
def _hook(frame, event, _arg):
    caller = frame.f_back
    if event == "call" and caller is not None and frame.f_code.co_filename[:1] == "/" \\
            and caller.f_code.co_filename[:4] in ("row ", "<str"):
        _calls.append(_record(frame))
'''


_FOUND: dict | None = None


def target(records: list) -> str | None:
    """The entry point a row exercised: the last of its calls that is in the catalogue."""
    global _FOUND
    if _FOUND is None:
        found = catalogue()
        _FOUND = (found, _index(found))
    for record in reversed(records):
        name = name_of(tuple(record), *_FOUND)
        if name is not None:
            return name
    return None

