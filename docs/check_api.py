"""Check the built site against the package: every public name documented, no broken link.

Run after the build (``make docs`` does): ``python docs/check_api.py docs/_build/html``.
Fails (exit 1, listing each problem) when

* a public module (any module whose dotted name has no part starting with ``_``) has no
  page or no docstring;
* a public name (``__all__`` of every public module, ``discrepancy.__all__`` first; the
  classes, functions and ``#:``-documented constants of a module without ``__all__``) has
  no docstring, or no anchor on its page, or is not linked from the page of a module that
  exports it;
* a public method or property of a documented class has no docstring or no anchor;
* a link or image inside the site points to a missing file or a missing anchor.

External links are not checked: the build machine has no network (``sphinx-build -b
linkcheck`` does it where there is one).
"""
from __future__ import annotations

import inspect
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))

from api_catalogue import Catalogue, attribute_docs  # noqa: E402

PACKAGE = "discrepancy"


class _Page(HTMLParser):
    """Ids, links and image sources of one HTML page."""

    def __init__(self):
        super().__init__()
        self.ids, self.links, self.images = set(), [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "a" and attrs.get("href"):
            self.links.append(attrs["href"])
        if tag == "img" and attrs.get("src"):
            self.images.append(attrs["src"])


def read_site(root: Path) -> dict[Path, _Page]:
    pages = {}
    for path in sorted(root.rglob("*.html")):
        page = _Page()
        page.feed(path.read_text(encoding="utf-8"))
        pages[path.resolve()] = page
    return pages


def _docstring(entry) -> str:
    obj = entry.obj
    if entry.kind == "data":
        return next((text for module in [entry.module] + [a.rsplit(".", 1)[0]
                                                         for a in entry.aliases]
                     if (text := attribute_docs(module).get(entry.name))), "")
    doc = obj.__doc__ or ""          # a class's own docstring, never its base class's
    if inspect.isclass(obj) and doc.startswith(f"{obj.__name__}("):
        return ""                    # the signature a dataclass writes when there is none
    return doc.strip()


def _public_members(cls, inherited: bool) -> list[str]:
    """Methods and properties a reader of ``cls``'s page sees, defined in the package."""
    owners = [c for c in cls.__mro__ if c.__module__.split(".")[0] == PACKAGE]
    if not inherited:
        owners = owners[:1] if owners and owners[0] is cls else []
    names = []
    for owner in owners:
        for name, value in vars(owner).items():
            if name.startswith("_") or name in names:
                continue
            if isinstance(value, (property, staticmethod, classmethod)) or \
                    inspect.isfunction(value):
                names.append(name)
    return names


def check_names(catalogue: Catalogue, root: Path, pages) -> tuple[list[str], dict]:
    problems, counts = [], {"modules": 0, "names": 0, "members": 0}
    api = root / "api"
    for module in catalogue.modules:
        page = pages.get((api / f"{module}.html").resolve())
        counts["modules"] += 1
        if page is None or f"module-{module}" not in page.ids:
            problems.append(f"module {module}: no page api/{module}.html")
        if not (inspect.getmodule(sys.modules[module]).__doc__ or "").strip():
            problems.append(f"module {module}: no docstring")
    for entry in catalogue.entries.values():
        if entry.kind == "module":
            continue
        counts["names"] += 1
        where = api / "generated" / f"{entry.home}.html" if entry.own_page else \
            api / f"{entry.module}.html"
        page = pages.get(where.resolve())
        if not _docstring(entry):
            problems.append(f"{entry.home}: no docstring")
        if page is None or entry.home not in page.ids:
            problems.append(f"{entry.home}: no anchor on {where.relative_to(root)}")
            continue
        if entry.kind in ("class", "exception"):
            inherited = entry.own_page and entry.kind == "class"
            for member in _public_members(entry.obj, inherited):
                counts["members"] += 1
                if not inspect.getdoc(getattr(entry.obj, member)):
                    problems.append(f"{entry.home}.{member}: no docstring")
                elif f"{entry.home}.{member}" not in page.ids:
                    problems.append(f"{entry.home}.{member}: no anchor on "
                                    f"{where.relative_to(root)}")
    for module in catalogue.modules:
        page = pages.get((api / f"{module}.html").resolve())
        links = {urlsplit(h).fragment for h in page.links} if page else set()
        for name, entry in catalogue.exported_entries(module):
            if entry.kind != "module" and entry.home not in links and \
                    f"{entry.home}" not in (page.ids if page else ()):
                problems.append(f"{module}.{name}: not linked from api/{module}.html")
    return problems, counts


def check_links(root: Path, pages) -> tuple[list[str], int]:
    problems, checked = [], 0
    for path, page in pages.items():
        for ref in page.links + page.images:
            parts = urlsplit(ref)
            if parts.scheme or ref.startswith(("//", "mailto:", "javascript:")):
                continue                                  # external: not checkable offline
            checked += 1
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                problems.append(f"{path.relative_to(root.resolve())}: broken link {ref}")
            elif parts.fragment and target.suffix == ".html" and \
                    unquote(parts.fragment) not in pages[target].ids:
                problems.append(f"{path.relative_to(root.resolve())}: no anchor {ref}")
    return problems, checked


def main(argv=None) -> int:
    root = Path((argv or sys.argv[1:] or ["docs/_build/html"])[0])
    pages = read_site(root)
    catalogue = Catalogue(PACKAGE)
    problems, counts = check_names(catalogue, root, pages)
    link_problems, n_links = check_links(root, pages)
    top = [e for e in catalogue.entries.values() if e.module == PACKAGE]
    figures = list((root / "_images").glob("sphx_glr_*")) if (root / "_images").exists() \
        else []
    examples = [p for p in (root / "auto_examples").glob("*.html")
                if p.stem not in ("index", "sg_execution_times")]
    print(f"site: {len(pages)} HTML pages ({len(list((root / 'api').rglob('*.html')))} API "
          f"pages, {len(examples)} gallery examples), {len(figures)} gallery figures")
    print(f"API: {counts['modules']} public modules, {counts['names']} public names "
          f"({len(top)} of them in {PACKAGE}.__all__, each on api/generated/<name>.html), "
          f"{counts['members']} public methods and properties")
    print(f"links: {n_links} links and images inside the site checked (external links are "
          "not: no network)")
    for problem in problems + link_problems:
        print("  FAIL", problem)
    if problems or link_problems:
        print(f"{len(problems)} undocumented or unlinked names, {len(link_problems)} broken "
              "links")
        return 1
    print("every public name documented and linked; no broken internal link")
    return 0


if __name__ == "__main__":
    sys.exit(main())
