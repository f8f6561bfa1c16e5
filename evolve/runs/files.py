"""Reading and writing the files of runs and sweeps: whole-or-nothing writes with the user's
permissions, and YAML whose errors fit on one line."""

from __future__ import annotations

from pathlib import Path

import yaml

from tsim.errors import SgrError
from tsim.files import atomic_write

__all__ = ["atomic_write", "read_yaml", "yaml_problem"]


def yaml_problem(exc: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: what and where (PyYAML's own message spans several)."""
    mark = getattr(exc, "problem_mark", None)
    what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"{what} at line {mark.line + 1}, column {mark.column + 1}" if mark else what


def read_yaml(path: Path, what: str = "file") -> object:
    """The parsed YAML file; ValueError naming the file when it is missing, not text or not YAML."""
    path = Path(path)
    if not path.is_file():
        raise SgrError(f"{what} not found: {path}")
    try:
        return yaml.safe_load(path.read_text())
    except UnicodeDecodeError:
        raise SgrError(f"{path}: not a text file") from None
    except yaml.YAMLError as exc:
        raise SgrError(f"{path}: not valid YAML: {yaml_problem(exc)}") from None
