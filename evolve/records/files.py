"""Reading and writing the files of runs and sweeps: whole-or-nothing writes with the user's
permissions, YAML whose errors fit on one line, and JSON records laid out for reading."""

from __future__ import annotations

import json
from pathlib import Path

import yaml

from tsim.errors import SgrError
from tsim.files import CONFIG_CAP, RECORD_CAP, atomic_write, read_text

__all__ = ["atomic_write", "read_yaml", "record_json", "yaml_problem"]


def yaml_problem(exc: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: what and where (PyYAML's own message spans several)."""
    mark = getattr(exc, "problem_mark", None)
    what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"{what} at line {mark.line + 1}, column {mark.column + 1}" if mark else what


class _NoAliases(yaml.SafeLoader):
    """safe_load's loader, refusing aliases (`*name`): a config has no use for them, and nested
    ones expand a kilobyte of YAML into gigabytes (a "billion laughs")."""

    def compose_node(self, parent, index):  # noqa: ANN001, ANN201 (PyYAML's signature)
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(None, None, "aliases (*name) are not read in sgr's files",
                                              event.start_mark)
        return super().compose_node(parent, index)


def load_yaml(text: str) -> object:
    """`yaml.safe_load(text)` without aliases (`_NoAliases`, a SafeLoader): what every sgr file is
    read with."""
    loader = _NoAliases(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def read_regular(path: Path, cap: int = RECORD_CAP) -> str:
    """A file's text, read from a folder sgr did not make (tsim/files.py `read_text`): SgrError
    naming it unless it is a regular file, not a link, of at most `cap` bytes; a FIFO or a device
    (a champion.json linked to /dev/zero) would never end."""
    return read_text(path, cap)


def read_yaml(path: Path, what: str = "file", *, follow: bool = True, cap: int = CONFIG_CAP) -> object:
    """The parsed YAML file; SgrError naming the file when it is missing, not a regular file (a FIFO,
    a device), over `cap` bytes, not text or not YAML. `follow`: read through a symbolic link (a
    file the user names); False for a file inside a folder, where a link is refused."""
    path = Path(path)
    if not path.exists() and (follow or not path.is_symlink()):
        raise SgrError(f"{what} not found: {path}")
    try:
        return load_yaml(read_text(path, cap, follow=follow))
    except UnicodeDecodeError:
        raise SgrError(f"{path}: not a text file") from None
    except yaml.YAMLError as exc:
        raise SgrError(f"{path}: not valid YAML: {yaml_problem(exc)}") from None


def record_json(obj: object, indent: int = 1) -> str:
    """`obj` as JSON with its objects and lists of containers indented, and every list or object of
    plain values on one line (a body row, a column of numbers, a gene): as readable as
    `json.dumps(obj, indent=1)` at a third of its size for a champion. Parses to the same data."""
    return _layout(obj, indent, 0)


def _layout(obj: object, indent: int, depth: int) -> str:
    if isinstance(obj, dict | list) and any(isinstance(v, dict | list) for v in
                                            (obj.values() if isinstance(obj, dict) else obj)):
        pad, inner = " " * (indent * depth), " " * (indent * (depth + 1))
        if isinstance(obj, dict):
            items = [f"{inner}{json.dumps(str(k))}: {_layout(v, indent, depth + 1)}" for k, v in obj.items()]
            return "{\n" + ",\n".join(items) + "\n" + pad + "}"
        items = [inner + _layout(v, indent, depth + 1) for v in obj]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(obj)
