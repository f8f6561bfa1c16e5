"""Layers talk through public names: no module reads or writes another top-level package's private
names (`x._name` where x comes from another of tsim, tasks, evolve, sgr and tests). A test module
under tests/<pkg>/ may reach <pkg>'s own (white-box tests of internals); tests/tasks may not reach
into tsim, say.

Where x comes from, read from the module's own text: a name imported from another package, or a
name or `self.attr` assigned the result of calling one (`self.sim = BatchSim(...)`). Besides, a
private name that only other packages define (`def _name`, `_name = ...`, `self._name = ...`)
counts as theirs whatever x is."""

import ast
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("tsim", "tasks", "parity", "evolve", "sgr", "tests")


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _files(pkg: str) -> list[Path]:
    return sorted((ROOT / pkg).rglob("*.py"))


def defined_names(tree: ast.AST) -> set[str]:
    """The private names a module defines: functions, classes, assigned names and self/cls
    attributes."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef) and _private(node.name):
            out.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store) and _private(node.id):
            out.add(node.id)
        elif (isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) and _private(node.attr)
              and isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")):
            out.add(node.attr)
    return out


@cache
def owners() -> dict[str, set[str]]:
    """Private name -> the packages that define it."""
    out: dict[str, set[str]] = {}
    for pkg in PACKAGES:
        for f in _files(pkg):
            for name in defined_names(ast.parse(f.read_text())):
                out.setdefault(name, set()).add(pkg)
    return out


def _dotted(node: ast.AST) -> str | None:
    """`a`, `self.sim`, ... as text; None for anything else."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute) and (base := _dotted(node.value)) is not None:
        return f"{base}.{node.attr}"
    return None


def foreign(tree: ast.AST, mine: set[str]) -> dict[str, str]:
    """Names and `self.attr`s of a module that come from another package -> that package."""
    out: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if (top := a.name.split(".")[0]) in PACKAGES and top not in mine:
                    out[a.asname or top] = top
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            if (top := node.module.split(".")[0]) in PACKAGES and top not in mine:
                out.update({a.asname or a.name: top for a in node.names})
    for node in ast.walk(tree):  # x = Foreign(...), self.x = module.Foreign(...)
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call):
            func = _dotted(node.value.func)
            top = out.get(func.split(".")[0]) if func else None
            for target in node.targets:
                if top and (name := _dotted(target)) is not None:
                    out[name] = top
    return out


def crossings(source: str, path: Path, owned: dict[str, set[str]]) -> list[str]:
    """`file:line: .name (pkg's)` for each access in `source` (the file `path`) to another
    package's private name."""
    rel = path.relative_to(ROOT)
    mine = {rel.parts[0]} | ({rel.parts[1]} if rel.parts[0] == "tests" and len(rel.parts) > 2 else set())
    tree = ast.parse(source)
    theirs = foreign(tree, mine)
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            whose = {theirs[x]} if (x := _dotted(node.value)) in theirs else owned.get(node.attr, set())
            if whose and not whose & mine:
                out.append(f"{rel}:{node.lineno}: .{node.attr} ({', '.join(sorted(whose))}'s)")
    return out


def test_no_package_reaches_into_another_packages_private_names():
    owned = owners()
    assert {"_pos0", "_obj_offsets", "_counts0", "_serial"} <= set(owned)  # the walk found tsim's
    bad = [c for pkg in PACKAGES for f in _files(pkg) for c in crossings(f.read_text(), f, owned)]
    assert not bad, "\n".join(bad)


def test_a_crossing_put_back_is_found():
    """The checker fails on today's fixed crossings when they come back: tasks reading BatchSim's
    `_pos0` and `_obj_offsets`, sgr.evogym writing `_counts0`, tsim's tests setting `_serial`
    from tests/evolve."""
    owned = owners()
    env = ROOT / "tasks" / "env.py"
    text = env.read_text()
    assert not crossings(text, env, owned)
    back = text.replace("self.sim.initial_positions[", "self.sim._pos0[").replace(
        "self.sim.object_offsets(k)", "np.array(self.sim._obj_offsets[k])")
    assert sorted(c.split(": ", 1)[1] for c in crossings(back, env, owned)) == ["._obj_offsets (tsim's)",
                                                                                "._pos0 (tsim's)"]
    evosim = ROOT / "sgr" / "evogym" / "sim.py"
    assert crossings(evosim.read_text().replace("self._bs.ignore_robot_self_collisions()",
                                                "self._bs._counts0[:, 4] = 0"), evosim, owned)
    kernels = ROOT / "tests" / "tsim" / "test_kernels.py"  # tsim's own tests may reach tsim's names
    assert not crossings(kernels.read_text() + "\nsim._serial = True\n", kernels, owned)
    elsewhere = ROOT / "tests" / "evolve" / "test_x.py"  # others may not
    assert crossings("from tsim.sim import BatchSim\nsim = BatchSim(w, b, o)\nsim._serial = True\n",
                     elsewhere, owned)
