"""Champion files of an older sgr rewritten in today's compact layout, holding the very same robot.

Older champion files hold SGR's controller as JSON numbers (~45 KB at 5x5, ~0.5 MB at 10x10),
direct NEAT's network node by node, and the genome as an object per gene, one value per line. They
load as they are (`evolve.methods.formats.controller_of` reads every format). This rewrites them as
sgr now writes them, for a tree that must stay small (tests/test_tree_size.py): the controller as
its genome's decoding (SGR, evolve/methods/sgr/record.py) or compiled form (direct,
`GraphController.to_derived_json`) where that gives it back exactly, the genome by columns, lists
of plain values on one line (`record_json`). Every other key is kept as it is, and a controller that
would not come back exactly stays in full, so a rewritten file loads as the same robot, bit for bit,
and replays to the same returns.

    sgr migrate docs   # every champion*.json below (or: python -m evolve.records.compact PATH...)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from evolve.methods import METHODS
from evolve.methods.formats import controller_of
from evolve.methods.sgr import record as sgr_record
from evolve.nn.dense import DenseController
from evolve.nn.genome_record import CONNECTION_COLUMNS, NODE_COLUMNS, as_columns, genes
from evolve.nn.graph import GraphController
from evolve.records.files import atomic_write, read_regular, read_yaml, record_json

MALFORMED = (KeyError, TypeError, ValueError, IndexError)


def same_controller(a, b) -> bool:
    """Whether two controllers compute the same, bit for bit: the same numbers in the same places."""
    if isinstance(a, DenseController) and isinstance(b, DenseController):
        return (sgr_record.digest(a) == sgr_record.digest(b) and a.activations == b.activations
                and a.input_size == b.input_size and a.action_cells.tolist() == b.action_cells.tolist()
                and [W.shape for W in a.weights] == [W.shape for W in b.weights])
    if isinstance(a, GraphController) and isinstance(b, GraphController):
        return a.to_json() == b.to_json()
    return False


def compact_record(record: dict, raw: dict | None = None) -> dict:
    """`record` in today's layout (module docstring); `raw` is its run's config.yaml, when
    there is one (SGR's decoder settings). Raises nothing for a record it cannot improve: it comes
    back with what could not be rewritten exactly left as it was."""
    out = dict(record)
    genome = record.get("genome")
    if isinstance(genome, dict):
        try:
            cols = as_columns(genome)
            if (genes(cols["nodes"], NODE_COLUMNS) == genes(genome["nodes"], NODE_COLUMNS) and
                    genes(cols["connections"], CONNECTION_COLUMNS) == genes(genome["connections"],
                                                                            CONNECTION_COLUMNS)):
                out["genome"] = cols
        except MALFORMED:
            pass
    method = METHODS.get(record.get("method")) if isinstance(record.get("method"), str) else None
    try:
        before = controller_of(record)
        candidate = None if method is None else method.compact_controller(record, before, raw)
        if candidate is None:  # the method's format is as short as it gets, or none is known
            return out
        if same_controller(before, controller_of({**out, "controller": candidate})):
            out["controller"] = candidate
    except MALFORMED:
        pass
    return out


def compact_file(path: str | Path) -> tuple[int, int]:
    """Rewrite one champion file in today's layout (`compact_record`, with the config.yaml beside
    it); returns its size in bytes before and after. The file is replaced only when the new text
    reads back as a record whose controller is the old one's, bit for bit."""
    path = Path(path)
    text = read_regular(path)
    record = json.loads(text)
    if not isinstance(record, dict):  # not a champion record: left as it is
        return len(text.encode()), len(text.encode())
    cfg_file = path.parent / "config.yaml"
    raw = read_yaml(cfg_file, follow=False) if cfg_file.is_file() else None
    new = record_json(compact_record(record, raw if isinstance(raw, dict) else None))
    if new == text:
        return len(text.encode()), len(text.encode())
    again = json.loads(new)
    def kept(r: dict) -> dict:
        return {k: v for k, v in r.items() if k not in ("genome", "controller")}

    if kept(again) != kept(record):
        raise AssertionError(f"{path}: the rewrite changed a key it must keep")
    if "controller" in record and not same_controller(controller_of(record), controller_of(again)):
        raise AssertionError(f"{path}: the rewritten controller differs")
    atomic_write(path, new.encode(), inside=path.parent)
    return len(text.encode()), len(new.encode())


def champion_files(paths: list[str | Path]) -> list[Path]:
    """The champion files (champion*.json) named or below the folders named."""
    out: list[Path] = []
    for p in map(Path, paths):
        out += [p] if p.is_file() else sorted(p.rglob("champion*.json"))
    return out


def main(argv: list[str] | None = None) -> int:
    """`python -m evolve.records.compact PATH...`: rewrite every champion file there; prints the bytes
    before and after."""
    paths = argv if argv is not None else sys.argv[1:]
    print("note: python -m evolve.records.compact is an alias of: sgr migrate PATH (one folder; it also "
          "converts an older sgr's pickles, with --trust-pickle)", file=sys.stderr)
    missing = [p for p in paths if not Path(p).exists()]
    if not paths or missing:
        what = "no such file or folder: " + ", ".join(missing) if missing else "name files or folders"
        print(f"error: {what} (usage: python -m evolve.records.compact PATH...)", file=sys.stderr)
        return 2
    files = champion_files(paths)
    before = after = 0
    for f in files:
        try:
            b, a = compact_file(f)
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            print(f"error: {f}: not a readable JSON file ({exc}); the files before it are rewritten",
                  file=sys.stderr)
            return 2
        before, after = before + b, after + a
        print(f"{f}: {b} -> {a} bytes")
    print(f"{len(files)} champion files: {before} -> {after} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
