"""What the API reference must cover, found by walking the package (no hand-kept lists).

A *public module* is every module of the package whose dotted name has no part starting with
``_``. A module's *public names* are its ``__all__``; a module without ``__all__`` exports
the classes and functions it defines (its constants are implementation details).

Every object is documented once, at its *home*: the shortest public path users import it
from. Names in the package's ``__all__`` live there (``discrepancy.DiscrepancyModel``), then
names in a subpackage's or module's ``__all__`` (shallowest first), then the module that
defines the object. Other paths to the same object (``discrepancy.models.DiscrepancyModel``,
``discrepancy.models.discrepancy_model.DiscrepancyModel``) link to the home.

Used by the Sphinx extension that writes the pages (``api_pages.py``) and by the check of
the built site (``check_api.py``), so both agree on what "every public name" means.
"""
from __future__ import annotations

import importlib
import inspect
import pkgutil
from dataclasses import dataclass, field

KINDS = ("module", "class", "exception", "function", "data")


@dataclass
class Entry:
    """One documented object: its home name, kind, and the public paths that export it."""

    home: str
    kind: str
    obj: object
    own_page: bool                       # names of an __all__ get a page of their own
    aliases: list[str] = field(default_factory=list)

    @property
    def module(self) -> str:
        return self.home.rsplit(".", 1)[0]

    @property
    def name(self) -> str:
        return self.home.rsplit(".", 1)[1]


def kind_of(obj) -> str:
    if inspect.ismodule(obj):
        return "module"
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if inspect.isfunction(obj) or inspect.isbuiltin(obj):
        return "function"
    return "data"


def public_modules(package: str) -> list[str]:
    """The package and every public submodule, imported (an import error fails loudly)."""
    root = importlib.import_module(package)
    names = [package] + sorted(
        info.name for info in pkgutil.walk_packages(root.__path__, package + ".")
        if not any(part.startswith("_") for part in info.name.split(".")))
    for name in names:
        importlib.import_module(name)
    return names


def exported_names(module) -> list[str]:
    """``__all__``, or the classes and functions the module defines itself and the
    constants it documents with a ``#:`` comment (autodoc's convention)."""
    if hasattr(module, "__all__"):
        return list(module.__all__)
    documented = attribute_docs(module.__name__)
    return sorted(name for name, obj in vars(module).items()
                  if not name.startswith("_") and (
                      (kind_of(obj) in ("class", "exception", "function")
                       and getattr(obj, "__module__", None) == module.__name__)
                      or (kind_of(obj) == "data" and name in documented)))


def attribute_docs(module_name: str) -> dict[str, str]:
    """``{name: text}`` of the module-level ``#:`` comments (and docstrings after
    assignments) of a module, as autodoc reads them."""
    from sphinx.errors import PycodeError
    from sphinx.pycode import ModuleAnalyzer

    try:
        docs = ModuleAnalyzer.for_module(module_name).find_attr_docs()
    except PycodeError:
        return {}
    return {name: "\n".join(lines).strip() for (scope, name), lines in docs.items()
            if scope == ""}


def _key(name: str, obj):
    # data (numbers, None, tuples) are not identified by identity alone: also by their name
    return ("data", name, id(obj)) if kind_of(obj) == "data" else ("object", id(obj))


class Catalogue:
    """Every public module and name of ``package`` with its home (see the module docstring)."""

    def __init__(self, package: str):
        self.package = package
        self.modules = public_modules(package)
        self.entries: dict[tuple, Entry] = {}
        self.exports: dict[str, list[tuple[str, tuple]]] = {m: [] for m in self.modules}
        self.submodules: dict[str, list[str]] = {
            m: [s for s in self.modules if s.rsplit(".", 1)[0] == m and s != m]
            for m in self.modules}
        with_all = [m for m in self.modules if hasattr(importlib.import_module(m), "__all__")]
        rest = [m for m in self.modules if m not in with_all]
        ordered = sorted(with_all, key=lambda m: (m != package, m.count("."), m)) + rest
        for module_name in ordered:
            module = importlib.import_module(module_name)
            for name in exported_names(module):
                self._add(module_name, module, name, own_page=module_name in with_all)
        for module_name, exports in self.exports.items():
            for name, key in exports:
                entry, path = self.entries.get(key), f"{module_name}.{name}"
                if entry is not None and path != entry.home and path not in entry.aliases:
                    entry.aliases.append(path)

    def _add(self, module_name, module, name, *, own_page):
        obj = getattr(module, name)
        path = f"{module_name}.{name}"
        key = _key(name, obj)
        if inspect.ismodule(obj):           # a submodule listed in __all__: its own page
            self.entries.setdefault(key, Entry(obj.__name__, "module", obj, True))
        # a name that is also a module's (a function shadowing its submodule) cannot be both
        # pages: it is documented at its next path, its defining module's
        elif key not in self.entries and path not in self.modules:
            self.entries[key] = Entry(path, kind_of(obj), obj,
                                      own_page and kind_of(obj) != "data")
        self.exports[module_name].append((name, key))

    def exported_entries(self, module_name: str) -> list[tuple[str, Entry]]:
        """``(name, entry)`` for every name ``module_name`` exports."""
        return [(name, self.entries[key]) for name, key in self.exports[module_name]
                if key in self.entries]

    def home_of(self, obj, name: str | None = None) -> str | None:
        """The documented name of ``obj`` (found under ``name`` when it is data)."""
        if inspect.ismodule(obj):
            return obj.__name__ if obj.__name__ in self.modules else None
        entry = self.entries.get(_key(name or "", obj))
        return None if entry is None else entry.home

    def homed_in(self, module_name: str) -> list[Entry]:
        """The entries whose home is ``module_name``."""
        return [e for e in self.entries.values()
                if e.kind != "module" and e.module == module_name]


def locate(path: str):
    """``(owner, attribute, object)`` for a dotted path (the longest importable module
    prefix, then attributes), or None."""
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        break
    else:
        return None
    owner = None
    for part in parts[i:]:
        owner, obj = obj, getattr(obj, part, _MISSING)
        if obj is _MISSING:
            return None
    return owner, parts[-1], obj


_MISSING = object()


def documented_name(catalogue: Catalogue, path: str) -> str | None:
    """Where ``path`` (any public or private path to a package object) is documented."""
    found = locate(path)
    if found is None:
        return None
    owner, attribute, obj = found
    home = catalogue.home_of(obj, attribute)
    if home is None and inspect.isclass(owner):     # a method, property or attribute
        owner_home = catalogue.home_of(owner)
        home = None if owner_home is None else f"{owner_home}.{attribute}"
    return home
