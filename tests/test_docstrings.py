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
