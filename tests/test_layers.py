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
    # fitting/ turns data into Gram statistics and selection/ chooses supports from them, both
    # without knowing a model class; hybrid/ holds the model's parts the estimators share;
    # the model drives them all (a model passes its make_setup down), and what takes a
    # model as a whole (the streaming and Dask faces, choose_procedure) sits above it
    order = ["errors", "constraints", "base", "registry", "symbolic", "runge_kutta", "data",
             "differentiation", "libraries", "optimizers", "fitting", "selection", "hybrid",
             "estimation", "models", "streaming", "distributed", "procedures", "pde", "energy",
             "systems", "control", "plots", "cli"]
    rank = {name: i for i, name in enumerate(order)}
    for module, targets in graph().items():
        layer = module.split(".")[1] if "." in module else None
        for target in targets:
            other = target.split(".")[1] if "." in target else None
            if layer in rank and other in rank:
                assert rank[other] <= rank[layer], f"{module} imports {target}"


def test_model_parts_never_import_the_model_or_a_higher_part():
    # inside models/: core/ and simulate/ are the parts below, outputs/ and files/ build on
    # them (never on each other), and only the model class (discrepancy_model.py) takes all
    rank = {"core": 0, "simulate": 0, "outputs": 1, "files": 1, "discrepancy_model": 2}
    for module, targets in graph().items():
        parts = module.split(".")
        if parts[1:2] != ["models"] or len(parts) < 3 or parts[2] not in rank:
            continue
        for target in targets:
            other = target.split(".")
            if other[1:2] != ["models"] or len(other) < 3 or other[2] == parts[2]:
                continue
            assert other[2] in rank, f"{module} imports {target}"
            assert rank[other[2]] < rank[parts[2]], f"{module} imports {target}"
