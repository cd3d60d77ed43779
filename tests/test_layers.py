"""The package's import graph: no cycles (counting imports inside functions too), and lower
layers never import higher ones."""
import ast
from pathlib import Path

import discrepancy

ROOT = Path(discrepancy.__file__).parent


def module_name(path: Path) -> str:
    parts = ["discrepancy", *path.relative_to(ROOT).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> set[str]:
    """Modules of this package that ``path`` imports (relative imports resolved)."""
    here = module_name(path).split(".")
    package = here if path.name == "__init__.py" else here[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            found.add(module)
            found |= {f"{module}.{a.name}" for a in node.names}
    return {m for m in found if m.startswith("discrepancy.") or m == "discrepancy"}


def graph() -> dict[str, set[str]]:
    modules = {module_name(p): p for p in ROOT.rglob("*.py")}
    return {name: {m for m in imports(p) if m in modules and m != name}
            for name, p in modules.items()}


def test_no_import_cycles():
    edges = graph()
    # a package's __init__ only re-exports its own modules: cycles through it are not ones
    edges = {k: {m for m in v if not (k.startswith(m + ".") and m != "discrepancy")}
             for k, v in edges.items()}
    state, cycles = {}, []

    def visit(node, stack):
        state[node] = "open"
        for nxt in edges[node]:
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, [*stack, nxt])
        state[node] = "done"

    for node in sorted(edges):
        if node not in state:
            visit(node, [node])
    assert not cycles, cycles


def test_lower_layers_never_import_higher_ones():
    order = ["errors", "constraints", "base", "registry", "symbolic", "data", "differentiation",
             "libraries", "optimizers", "accumulate", "models", "selection", "streaming",
             "distributed", "pde", "estimation", "energy", "systems", "control", "plots", "cli"]
    rank = {name: i for i, name in enumerate(order)}
    allowed_up = {("models", "streaming"), ("models", "distributed"),   # fit dispatches to them
                  ("models", "estimation"),           # and fit_prediction_error to estimation
                  ("models", "selection")}   # and chooses terms by forecasts there
    for module, targets in graph().items():
        layer = module.split(".")[1] if "." in module else None
        for target in targets:
            other = target.split(".")[1] if "." in target else None
            if layer in rank and other in rank and rank[other] > rank[layer]:
                assert (layer, other) in allowed_up, f"{module} imports {target}"
