"""The layers: no import cycle among the project's modules (module-level or inside functions), and
each layer imports only the layers above it (tsim <- tasks <- evolve <- sgr: sgr, the face users
import, sits on top and nothing imports it)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("tsim", "tasks", "evolve", "sgr")
LAYER = {"tsim": 0, "tasks": 1, "evolve": 2, "sgr": 3}


def modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for f in (ROOT / pkg).rglob("*.py"):
            parts = f.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f
    return out


def imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Project modules `name` imports anywhere in its file; `from pkg import sub` counts as pkg.sub
    when sub is a module."""
    out = set()
    is_pkg = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import
                base = name.split(".")[: len(name.split(".")) - node.level + (1 if is_pkg else 0)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                out.add(f"{mod}.{a.name}" if f"{mod}.{a.name}" in known else mod)
    return {m for m in out if m in known and m != name}


def graph() -> dict[str, set[str]]:
    mods = modules()
    return {m: imports(m, p, set(mods)) for m, p in mods.items()}


def find_cycle(g: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for n in sorted(g[m]):
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state and (c := visit(n)):
                return c
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(g):
        if m not in state and (c := visit(m)):
            return c
    return None


def test_no_import_cycle():
    g = graph()
    assert len(g) > 30  # the walk found the project
    assert find_cycle(g) is None, " -> ".join(find_cycle(g))


def test_the_cycle_finder_finds_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_each_layer_imports_only_the_layers_above_it():
    bad = [f"{m} imports {n}" for m, deps in graph().items() for n in deps
           if LAYER[n.split(".")[0]] > LAYER[m.split(".")[0]]]
    assert not bad, bad


def test_nothing_below_sgr_imports_it():
    """sgr (and sgr.evogym) is the top layer: tsim, tasks and evolve never import it."""
    g = graph()
    assert any(m.startswith("sgr.evogym") for m in g)  # the walk found the package
    bad = [f"{m} imports {n}" for m, deps in g.items() for n in deps
           if n.split(".")[0] == "sgr" and m.split(".")[0] != "sgr"]
    assert not bad, bad
