"""Sphinx extension: the API reference, written from the package at every build.

Sphinx's ``autosummary`` would document an object once per path that exports it
(``discrepancy.DiscrepancyModel``, ``discrepancy.models.DiscrepancyModel``, its defining
module), which Sphinx reports as duplicate descriptions. This writes the pages from
:mod:`api_catalogue` instead: one page per public module (its docstring, its submodules,
tables of what it exports), one page per name of an ``__all__`` (``autoclass`` /
``autofunction`` with members), other names inline on their module's page; autodoc and
autosummary render them. A new module or name gets its page at the next build.

References written with any path to an object (``discrepancy.models.DiscrepancyModel``,
``~.dynamics.as_casadi``, ``FitSetup`` from inside a docstring of its module) are resolved
to its one page by the ``missing-reference`` handler below; what still does not resolve is
a broken link, which ``nitpicky`` with ``-W`` turns into a failed build.
"""
from __future__ import annotations

import inspect
import re
import sys
from pathlib import Path

from api_catalogue import Catalogue, attribute_docs, documented_name, locate
from sphinx import addnodes

OUT = "api"
GENERATED = "generated"
HEADINGS = {"module": "Modules", "class": "Classes", "exception": "Exceptions",
            "function": "Functions", "data": "Data"}
DIRECTIVES = {"class": "autoclass", "exception": "autoexception", "function": "autofunction"}


def _title(text: str, underline: str = "=") -> list[str]:
    return [text, underline * len(text), ""]


def _object_page(entry, catalogue) -> str:
    lines = [f".. title:: {entry.home}", "", *_title(entry.name),
             f".. currentmodule:: {entry.module}", "",
             f".. {DIRECTIVES[entry.kind]}:: {entry.name}"]
    if entry.kind == "class":
        lines += ["   :members:", "   :inherited-members:", "   :show-inheritance:"]
    elif entry.kind == "exception":
        lines += ["   :members:", "   :show-inheritance:"]
    lines.append("")
    if entry.aliases:
        lines += ["Also importable as " + ", ".join(f"``{a}``" for a in entry.aliases) + ".",
                  ""]
    lines += [f".. minigallery:: {entry.home}", "   :add-heading: Examples using this", ""]
    return "\n".join(lines)


def _data_block(entry) -> list[str]:
    doc, value = data_docstring(entry), repr(entry.obj)
    simple = isinstance(entry.obj, (int, float, str, tuple, type(None)))
    shown = [f"   :value: {value}"] if simple and len(value) < 80 else []
    return [f".. py:data:: {entry.name}", *shown, "",
            *["   " + line for line in doc.splitlines()], ""]


def data_docstring(entry) -> str:
    """The ``#:`` comment of a data name, from whichever module assigns it."""
    modules = [entry.module] + [a.rsplit(".", 1)[0] for a in entry.aliases]
    modules += [m for m in _defining_candidates(entry) if m not in modules]
    for module_name in modules:
        text = attribute_docs(module_name).get(entry.name)
        if text:
            return text
    return ""


def _defining_candidates(entry) -> list[str]:
    """Modules that bind the same object under the same name (where a constant is set)."""
    import sys

    return [name for name, module in list(sys.modules.items())
            if name.startswith(entry.home.split(".")[0] + ".") and module is not None
            and getattr(module, entry.name, None) is entry.obj]


def _relative(name: str, module_name: str) -> str:
    return name[len(module_name) + 1:] if name.startswith(module_name + ".") else name


def _module_page(module_name, catalogue) -> tuple[str, list]:
    lines = [*_title(module_name), f".. automodule:: {module_name}", "   :no-members:", "",
             f".. currentmodule:: {module_name}", ""]
    pages = []
    homed = catalogue.homed_in(module_name)
    for kind in ("class", "exception", "function", "data"):
        entries = [e for e in homed if e.kind == kind]
        if not entries:
            continue
        lines += _title(HEADINGS[kind], "-")
        own = [e for e in entries if e.own_page]
        if own:
            lines += [".. autosummary::", "   :nosignatures:", "",
                      *[f"   {e.name}" for e in own], "", ".. toctree::", "   :hidden:", "",
                      *[f"   {GENERATED}/{e.home}" for e in own], ""]
            pages += own
        for e in (e for e in entries if not e.own_page):
            if kind == "data":
                lines += _data_block(e)
            elif kind == "function":
                lines += [f".. autofunction:: {e.name}", ""]
            else:
                lines += [f".. {DIRECTIVES[kind]}:: {e.name}", "   :members:",
                          "   :show-inheritance:", ""]
    elsewhere = {e.home: e for name, e in catalogue.exported_entries(module_name)
                 if e.module != module_name and e.kind != "module"}
    if elsewhere:
        objects = sorted(h for h, e in elsewhere.items() if e.kind != "data")
        data = sorted(h for h, e in elsewhere.items() if e.kind == "data")
        lines += [*_title("Also available here", "-"),
                  f"Exported by ``{module_name}``, documented where users import them from:",
                  ""]
        if objects:        # autosummary would show a constant's type's docstring: not here
            lines += [".. autosummary::", "   :nosignatures:", "",
                      *[f"   {_relative(home, module_name)}" for home in objects], ""]
        lines += [f"* :data:`{home}`" for home in data] + [""]
    subs = catalogue.submodules[module_name]        # last: what users call comes first
    if subs:
        lines += [*_title("Submodules", "-"), ".. autosummary::", "",
                  *[f"   {_relative(s, module_name)}" for s in subs], "", ".. toctree::",
                  "   :hidden:", "", *[f"   {s}" for s in subs], ""]
    return "\n".join(lines), pages


_CATALOGUES: dict = {}


def _catalogue(app) -> Catalogue:
    """One catalogue per build (modules cannot be pickled with Sphinx's environment)."""
    if app.config.api_package not in _CATALOGUES:
        _CATALOGUES[app.config.api_package] = Catalogue(app.config.api_package)
    return _CATALOGUES[app.config.api_package]


def write_pages(app) -> None:
    """Write ``api/<module>.rst`` and ``api/generated/<name>.rst``; drop stale pages."""
    catalogue = _catalogue(app)
    root = Path(app.srcdir) / OUT
    (root / GENERATED).mkdir(parents=True, exist_ok=True)
    wanted = {}
    for module_name in catalogue.modules:
        text, pages = _module_page(module_name, catalogue)
        wanted[root / f"{module_name}.rst"] = text
        for entry in pages:
            wanted[root / GENERATED / f"{entry.home}.rst"] = _object_page(entry, catalogue)
    for path in list(root.glob("*.rst")) + list((root / GENERATED).glob("*.rst")):
        if path not in wanted:
            path.unlink()
    for path, text in wanted.items():
        if not path.exists() or path.read_text() != text:  # unchanged pages stay cached
            path.write_text(text)


def resolve_any_path(app, env, node, contnode):
    """Resolve a Python reference written with another path to the object's home."""
    if node.get("refdomain") != "py":
        return None
    catalogue = _catalogue(app)
    target = node["reftarget"]
    package = app.config.api_package
    for candidate in _candidates(target, node.get("py:module"), node.get("py:class")):
        if not (candidate == package or candidate.startswith(package + ".")):
            continue
        home = documented_name(catalogue, candidate)
        if home and home != target:
            domain = env.get_domain("py")
            found = domain.resolve_xref(env, node["refdoc"], app.builder, "obj", home, node,
                                        contnode)
            if found is not None:
                return found
    return None


def _candidates(target, module, cls):
    """Where a reference written in a docstring may point: absolute, then relative to the
    documented context and to the module that defines it (``.x`` climbs packages)."""
    stripped = target.lstrip(".")
    contexts = []
    if module:
        contexts.append(module)
        if cls:
            contexts.insert(0, f"{module}.{cls}")
            found = locate(f"{module}.{cls}")
            defining = getattr(found[2], "__module__", None) if found else None
            if defining:
                contexts += [f"{defining}.{cls.split('.')[0]}", defining]
    yield target
    for context in contexts:
        parts = context.split(".")
        for i in range(len(parts), 0, -1):
            yield ".".join(parts[:i]) + "." + stripped


def canonical_name(path: str) -> str | None:
    """The defining path of a documented object (``discrepancy.models.discrepancy_model.
    DiscrepancyModel.fit`` for ``discrepancy.DiscrepancyModel.fit``)."""
    found = locate(path)
    if found is None:
        return None
    owner, attribute, obj = found
    if inspect.isclass(owner):
        base = canonical_name(path.rsplit(".", 1)[0])
        return None if base is None else f"{base}.{attribute}"
    if inspect.isclass(obj) or inspect.isfunction(obj):
        return f"{obj.__module__}.{obj.__qualname__}"
    return None


def canonical_anchors(app, doctree) -> None:
    """Give every signature the anchor of its defining path as well: the source pages
    (viewcode) link to ``page.html#<defining path>``."""
    taken = {i for node in doctree.findall() if hasattr(node, "get")
             for i in node.get("ids", ())}
    for sig in doctree.findall(addnodes.desc_signature):
        module, fullname = sig.get("module"), sig.get("fullname")
        if not (module and fullname and sig["ids"]):
            continue
        canonical = canonical_name(f"{module}.{fullname}")
        if canonical and canonical not in taken:
            sig["ids"].append(canonical)
            taken.add(canonical)


def backlinks_to_defining_path(app):
    """Make viewcode's source pages link back to ``page.html#<defining path>``.

    viewcode keeps one anchor prefix per source module: the module under which the first of
    its objects happened to be read (``discrepancy`` for ``discrepancy.Grid``), and links
    every object of that source file to ``page.html#<prefix>.<name>``. The objects of one
    file may have different homes (``discrepancy.data.fields.FieldRun`` beside
    ``discrepancy.Grid``), so that anchor would not exist on their pages; the defining module
    is right for all of them (``canonical_anchors`` gives every signature that anchor)."""
    modules = getattr(app.env, "_viewcode_modules", {})
    for module_name, entry in modules.items():
        if entry:                       # (code, tags, used names, anchor prefix)
            modules[module_name] = (*entry[:3], module_name)
    return []


FIELD_WITH_NAMES = re.compile(r"^(\s*:(?:param|ivar|var|cvar|keyword|type|vartype) )"
                              r"([A-Za-z_][\w]*(?:, [A-Za-z_][\w]*)+):")


def join_field_names(app, what, name, obj, options, lines) -> None:
    """``Args:`` entries naming several parameters (``Q, R: weights``) become one field
    ``Q,R``: Sphinx would read ``:param Q, R:`` as a parameter R of type "Q,"."""
    for i, line in enumerate(lines):
        lines[i] = FIELD_WITH_NAMES.sub(lambda m: m[1] + m[2].replace(", ", ",") + ":", line)


def foreign_reference(app, domain, node) -> bool | None:
    """Let references into other projects through (they cannot be linked offline: no
    intersphinx inventories); ours must resolve."""
    if domain is None or domain.name != "py":
        return None
    target = node["reftarget"].lstrip(".~")
    head = target.split(".")[0]
    package = app.config.api_package
    if head != package and (head in app.config.api_foreign_aliases or head in sys.modules):
        return True
    return None


def setup(app):
    app.add_config_value("api_package", "", "env")
    app.add_config_value("api_foreign_aliases", (), "env")
    app.connect("builder-inited", write_pages)
    app.connect("missing-reference", resolve_any_path)
    app.connect("doctree-read", canonical_anchors)
    app.connect("html-collect-pages", backlinks_to_defining_path, priority=400)  # before viewcode
    app.connect("warn-missing-reference", foreign_reference)
    app.connect("autodoc-process-docstring", join_field_names, priority=600)  # after napoleon
    return {"parallel_read_safe": True, "parallel_write_safe": True}
