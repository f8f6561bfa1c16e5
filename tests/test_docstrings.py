"""Every public class, function and method of tsim, tasks, evolve and sgr has a docstring.

Public: a name not starting with `_`; checked are module-level functions and classes (also those
under a module-level `if`/`try`), and the methods (properties included) and nested classes of public
classes. Functions nested in functions are not API and are skipped.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("tsim", "tasks", "parity", "evolve", "sgr")
DEFS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)


def _defs(body: list[ast.stmt]):
    """Definitions in `body`, looking inside module- or class-level `if` and `try` blocks."""
    for node in body:
        if isinstance(node, DEFS):
            yield node
        elif isinstance(node, ast.If):
            yield from _defs(node.body + node.orelse)
        elif isinstance(node, ast.Try):
            yield from _defs(node.body + node.orelse + node.finalbody
                             + [s for h in node.handlers for s in h.body])


def _undocumented(body: list[ast.stmt], prefix: str):
    for node in _defs(body):
        if node.name.startswith("_"):
            continue
        name = prefix + node.name
        if ast.get_docstring(node) is None:
            yield node.lineno, name
        if isinstance(node, ast.ClassDef):
            yield from _undocumented(node.body, name + ".")


def missing_docstrings() -> list[str]:
    out = []
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            tree = ast.parse(path.read_text(), filename=str(path))
            rel = path.relative_to(ROOT).as_posix()
            out += [f"{rel}:{line}: {name}" for line, name in _undocumented(tree.body, "")]
    return out


def test_the_packages_are_found():
    assert all((ROOT / pkg / "__init__.py").is_file() for pkg in PACKAGES)


def test_every_public_definition_has_a_docstring():
    missing = missing_docstrings()
    assert not missing, (f"{len(missing)} public definitions without a docstring (say why it exists "
                         "or what a caller must know):\n" + "\n".join(missing))


def test_the_check_sees_what_it_should():
    src = '''
def pub(): pass
def _priv(): pass
class Pub:
    def meth(self): pass
    @property
    def prop(self): pass
    def _hidden(self): pass
class _Priv:
    def meth(self): pass
def outer():
    """Doc."""
    def inner(): pass
if True:
    def guarded(): pass
'''
    found = [name for _, name in _undocumented(ast.parse(src).body, "")]
    assert found == ["pub", "Pub", "Pub.meth", "Pub.prop", "guarded"]


# The public API (what the docs site's API pages render: each package's `__all__`, the public methods
# and properties of its classes, and the package's own docstring) reads as pyribs' does: a first line
# that says what, alone, then the details (Args/Returns/Raises where they help).
API_PACKAGES = ("tsim", "tasks", "evolve", "sgr.evogym")


def api_docstrings() -> dict[str, str]:
    """Every public API object's name -> its docstring (those with one)."""
    import importlib
    import inspect

    out = {}
    for pkg in API_PACKAGES:
        module = importlib.import_module(pkg)
        out[pkg] = inspect.getdoc(module) or ""
        for name in module.__all__:
            obj = getattr(module, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            out[f"{pkg}.{name}"] = obj.__doc__ and inspect.cleandoc(obj.__doc__) or ""
            if inspect.isclass(obj) and obj.__module__.split(".")[0] == pkg.split(".")[0]:
                for key, value in vars(obj).items():
                    if key.startswith("_") or not (inspect.isfunction(value) or isinstance(
                            value, property | classmethod | staticmethod)):
                        continue
                    fn = value.fget if isinstance(value, property) else getattr(value, "__func__", value)
                    if fn is not None and fn.__doc__:
                        out[f"{pkg}.{name}.{key}"] = inspect.cleandoc(fn.__doc__)
    return out


def summary_problem(doc: str) -> str | None:
    """Why `doc` does not open with a one-line summary, None when it does."""
    lines = doc.splitlines()
    if not lines or not lines[0].strip():
        return "no first line"
    if len(lines) > 1 and lines[1].strip():
        return "the first line runs on into a second (a summary is one line, then a blank line)"
    if not lines[0].rstrip().endswith((".", ":", "?", "!")):
        return "the first line is not a sentence"
    return None


def test_the_public_api_docstrings_open_with_a_one_line_summary():
    docs = api_docstrings()
    assert {"tsim.BatchSim", "tasks.BatchEnv", "evolve.Experiment", "sgr.evogym.EvoSim"} <= set(docs)
    bad = sorted(f"{name}: {why}" for name, doc in docs.items() if (why := summary_problem(doc)))
    assert not bad, f"{len(bad)} docstrings:\n" + "\n".join(bad)


def test_the_summary_rule_finds_an_essay():
    assert summary_problem("Run the batch.\n\nArgs:\n    n: steps.") is None
    assert summary_problem("Run the batch for n steps, which\nmay take long.") is not None
    assert summary_problem("") is not None
