"""The Python side's layering, read from the source: nn (torch networks and their export) is a
leaf that imports nothing of pydem; no import circle among the modules of pydem and nn; no
private name taken from another module. Imports inside functions count as much as those at the
top: a lazy import hides a tie, it does not remove it."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("pydem", "nn")


def modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the two packages."""
    out = {}
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(f.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = f
    return out


def imports(name: str, path: Path, known: dict[str, Path]) -> list[tuple[str, list[str], int]]:
    """(imported module, names taken from it, line) for every import statement of one module,
    relative imports resolved; only modules of the two packages are kept."""
    is_pkg = path.name == "__init__.py"
    here = name.split(".") if is_pkg else name.split(".")[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] in PACKAGES:
                    out.append((a.name, [], node.lineno))
        elif isinstance(node, ast.ImportFrom):
            base = (here[:len(here) - node.level + 1] if node.level else []) + (node.module.split(".") if node.module else [])
            mod = ".".join(base)
            if not base or base[0] not in PACKAGES:
                continue
            for a in node.names:  # `from pkg import module` imports the module, not the package
                sub = f"{mod}.{a.name}"
                if sub in known:
                    out.append((sub, [], node.lineno))
                else:
                    out.append((mod, [a.name], node.lineno))
    return out


def graph() -> tuple[dict[str, set[str]], list[str]]:
    known = modules()
    edges, private = {m: set() for m in known}, []
    for name, path in known.items():
        for mod, names, line in imports(name, path, known):
            if mod in known and mod != name:
                edges[name].add(mod)
            for n in names:
                if n.startswith("_") and not n.startswith("__") and mod != "pydem" and mod.split(".")[0] == "pydem":
                    private.append(f"{path.relative_to(ROOT)}:{line} takes {n} from {mod}")
    return edges, private


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def ties_to_parent_packages(edges):
    """A module's import of its own package's __init__ (for `from . import _lib`) is a tie to
    the package object, not a layer: the package's __init__ is excluded from the circle check
    when it only re-exports (pydem/__init__ re-exports Domain and loads the binding)."""
    return {m: {w for w in ws if not m.startswith(w + ".")} for m, ws in edges.items()}


def test_nn_imports_nothing_of_pydem():
    edges, _ = graph()
    wrong = sorted(f"{m} -> {w}" for m, ws in edges.items() if m.split(".")[0] == "nn" for w in ws
                   if w.split(".")[0] == "pydem")
    assert not wrong, f"nn must be a leaf (torch networks and their export): {wrong}"


def test_no_import_circle():
    found = circles(ties_to_parent_packages(graph()[0]))
    assert not found, f"import circles: {found}"


def test_no_private_name_taken_from_another_module():
    _, private = graph()
    assert not private, "\n".join(private)


def test_the_commands_do_not_reach_into_the_validation_harness():
    """pydem.calibration.synthetic makes and scores hidden-effect sets for the studies; no module
    of the package (the commands, --confirm included) depends on it."""
    edges, _ = graph()
    users = sorted(m for m, ws in edges.items() if "pydem.calibration.synthetic" in ws)
    assert not users, f"modules that import the validation harness: {users}"


def test_the_checks_see_a_circle_and_a_leaf_broken():
    """The checks themselves: a made-up graph with a circle is caught, a tree is not."""
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set(), "c": {"a", "b"}}) == []
    known = modules()
    assert "pydem.seed001.experiments" in known and "nn.cnn" in known
    taken = [(m, n) for m, n, _ in imports("pydem.seed001.report", known["pydem.seed001.report"], known)]
    assert ("pydem.seed001.store", ["FrameStore"]) in taken and ("pydem.report_page", []) in taken
