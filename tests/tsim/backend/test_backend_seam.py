"""The backend seam: precision and arch names are written in tsim/backend/tables.py only (the tables
that tsim.backend re-exports).

The rule (it can fail): in the library's code (tsim/, tasks/, evolve/, sgr/), a string literal whose
whole value is a precision's or an arch's name ("f64", "cuda", ...) is a decision taken outside the
seam (`arch == "cpu"`, `or "f64"`, a copied list of names), and fails this test. Allowed:
tsim/backend/tables.py itself; docstrings and comments (not string literals that code compares: a
docstring is the first statement of a module, class or function; comments are not in the syntax
tree); longer text that
merely mentions a name (help and error lines, "SGR_ARCH=cpu"); and a literal on a line marked
`# backend-seam: <why>`, for a name that is no arch (e.g. the library "cuda" that ctypes loads).
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from tsim import backend

ROOT = Path(__file__).resolve().parents[3]
PACKAGES = ("tsim", "tasks", "parity", "evolve", "sgr")
SEAM = ROOT / "tsim" / "backend" / "tables.py"
MARK = "# backend-seam:"
NAMES = frozenset({"f64", "f32", "cpu", "gpu", "cuda", "vulkan", "metal"})


def _docstrings(tree: ast.AST) -> set[int]:
    """ids of the docstring constants of a module and its classes and functions."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


def named_outside(source: str, path: str = "<text>") -> list[str]:
    """'path:line: "name"' for each string literal of `source` that is exactly a backend name, not a
    docstring and not on a line marked MARK."""
    tree = ast.parse(source)
    lines = source.splitlines()
    docs = _docstrings(tree)
    hits = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in NAMES
                and id(node) not in docs and MARK not in lines[node.lineno - 1]):
            hits.append(f"{path}:{node.lineno}: {node.value!r}")
    return hits


def test_backend_names_are_written_only_in_tsim_backends():
    """No module of the library but tsim/backend/tables.py writes a precision's or arch's name as a
    string literal (see this file's docstring for the rule)."""
    hits = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            if path != SEAM:
                hits += named_outside(path.read_text(), str(path.relative_to(ROOT)))
    assert not hits, ("backend names outside tsim/backend/tables.py (ask tsim.backend instead):\n"
                      + "\n".join(hits))


@pytest.mark.parametrize("code", ['if arch == "cpu":\n    pass\n', 'p = cfg.get("precision") or "f64"\n',
                                  'PRECISIONS = ("f64", "f32")\n', 'x = {"cuda": 1}\n',
                                  'def f():\n    """Doc."""\n    return "metal"\n'])
def test_the_rule_catches_a_name_in_code(code):
    """The grep fails on a comparison, a default, a copied list, a dict key and a return value."""
    assert named_outside(code)


@pytest.mark.parametrize("code", ['"""Runs on "cpu" or "cuda"."""\n', 'x = 1  # on "cpu" only\n',
                                  'def f():\n    """f32 or f64."""\n',
                                  'HELP = "SGR_ARCH=cpu, or f32"\n',
                                  'lib = find("cuda")  # backend-seam: a library name\n'])
def test_the_rule_lets_docs_comments_text_and_marked_lines_be(code):
    """Docstrings, comments, longer text and marked lines are not decisions."""
    assert named_outside(code) == []


def test_the_seam_names_every_precision_and_arch():
    """The seam's tables hold exactly the names the rule looks for, each row under its own name:
    a precision added to `PRECISIONS` or an arch to `ARCHS` is the grep's concern too."""
    assert set(backend.PRECISIONS) | set(backend.ARCHS) == NAMES
    assert all(p.name == k for k, p in backend.PRECISIONS.items())
    assert all(a.name == k for k, a in backend.ARCHS.items())
    assert backend.DEFAULT_PRECISION in backend.PRECISIONS and backend.DEFAULT_ARCH in backend.ARCHS


def test_precision_rows_match_numpy_types():
    """Each precision's numpy type has the width its name says (f64: 8 bytes, f32: 4)."""
    for name, p in backend.PRECISIONS.items():
        assert np.dtype(p.dtype).itemsize * 8 == int(name[1:])


def test_cli_choices_and_runtime_read_the_seam():
    """The CLI's --precision choices and tsim.backend.runtime's lists are the seam's, not copies."""
    from tasks.cli import PRECISIONS
    from tsim.backend import runtime

    assert PRECISIONS == tuple(backend.PRECISIONS)
    assert runtime.PRECISIONS == tuple(backend.PRECISIONS) and runtime.ARCHS == tuple(backend.ARCHS)
