"""elites.json, a map-elites run's archive as data: every elite's champion record (what
champion.json holds for the best one: body, controller, genome, fitness and how it was scored),
with its cell and descriptors, so any elite is a runnable robot (`load_champion(run, cell=(i, j))`).
Written by the run's `ArchiveFiles` reporter (evolve/runs/reporters.py, `elites_record`).

    {"format": "sgr-elites-1", "generation": g, "descriptors": ["actuator", "rigid"],
     "ranges": [[0, 1], [0, 1]], "resolution": [10, 10], "coverage": 0.31, "qd_score": 123.4,
     "elites": [{"cell": [i, j], "measures": {"actuator": 0.4, ...}, "champion": {...}}, ...]}
"""

from __future__ import annotations

import json
import numbers
from pathlib import Path

import numpy as np

from evolve.records.rundir import ELITES_FILE, ELITES_GZ
from tsim.errors import SgrError
from tsim.files import RECORD_CAP, read_gzip, read_text

FORMAT = "sgr-elites-1"


def elites_file(run_dir: str | Path) -> Path | None:
    """A run's archive file: elites.json, or in a results folder that keeps it compact elites.json.gz;
    None when it has neither."""
    for name in (ELITES_FILE, ELITES_GZ):
        f = Path(run_dir) / name
        if f.is_file():
            return f
    return None


def read_elites(run_dir: str | Path) -> dict:
    """A run's elites.json (or elites.json.gz) as read; SgrError when there is none or it is not one."""
    f = elites_file(run_dir)
    if f is None:
        raise SgrError(f"{run_dir} has no {ELITES_FILE}: only a map-elites run keeps an archive of elites")
    try:
        text = read_gzip(f, RECORD_CAP).decode() if f.name == ELITES_GZ else read_text(f, RECORD_CAP)
        data = json.loads(text)
    except (json.JSONDecodeError, UnicodeDecodeError, EOFError) as exc:
        raise SgrError(f"{f}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("elites"), list):
        raise SgrError(f"{f}: not an archive of elites (format {FORMAT})")
    bad = _first_bad_key(data)
    if bad is not None:
        raise SgrError(f"{f}: key {bad!r} is missing or not what an archive of elites holds")
    return data


def _number(x: object) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _ints(x: object) -> bool:
    return isinstance(x, list) and all(isinstance(i, int) and not isinstance(i, bool) for i in x)


def _first_bad_key(data: dict) -> str | None:
    """The first key of elites.json (module docstring) whose value is not of its kind, None when
    all are: what the report, the archive's picture and `--cell` read, so a damaged file is one line."""
    res = data.get("resolution")
    if not (_ints(res) and res):
        return "resolution"
    names = data.get("descriptors")
    if not (isinstance(names, list) and len(names) == len(res) and all(isinstance(n, str) for n in names)):
        return "descriptors"
    ranges = data.get("ranges")
    if not (isinstance(ranges, list) and len(ranges) == len(res)
            and all(isinstance(r, list) and len(r) == 2 and all(map(_number, r)) for r in ranges)):
        return "ranges"
    for key in ("generation", "coverage", "qd_score"):
        if not _number(data.get(key)):
            return key
    for j, e in enumerate(data["elites"]):
        if not isinstance(e, dict):
            return f"elites[{j}]"
        if not (_ints(e.get("cell")) and len(e["cell"]) == len(res)
                and all(0 <= c < r for c, r in zip(e["cell"], res, strict=True))):
            return f"elites[{j}].cell"
        m = e.get("measures")
        if not (isinstance(m, dict) and all(_number(v) for v in m.values())):
            return f"elites[{j}].measures"
        champ = e.get("champion")
        if not (isinstance(champ, dict) and _number(champ.get("fitness"))
                and isinstance(champ.get("body"), list)):
            return f"elites[{j}].champion"
    return None


def parse_cell(text: str) -> tuple[int, ...]:
    """A cell written "i,j" (`sgr render --cell`) as integers; SgrError otherwise."""
    try:
        cell = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise SgrError(f"a cell is its indices separated by commas (e.g. 3,4), got {text!r}") from None
    return cell


def elite_record(run_dir: str | Path, cell) -> dict:
    """The champion record of the elite in `cell` (a tuple of indices, or "i,j") of a run's archive;
    SgrError naming the cell when it is empty."""
    if isinstance(cell, np.ndarray):
        cell = cell.tolist()
    if not isinstance(cell, str) and not (isinstance(cell, tuple | list) and all(
            isinstance(i, numbers.Integral) and not isinstance(i, bool) for i in cell)):
        # (2.9, 1.7) was cell (2, 1)
        raise SgrError(f"a cell is a tuple of integer indices or 'i,j', got {cell!r}")
    cell = parse_cell(cell) if isinstance(cell, str) else tuple(int(i) for i in cell)
    data = read_elites(run_dir)
    for e in data["elites"]:
        if tuple(e["cell"]) == cell:
            return e["champion"]
    filled = ", ".join(",".join(map(str, e["cell"])) for e in data["elites"][:8])
    raise SgrError(f"{Path(run_dir) / ELITES_FILE}: no elite in cell {','.join(map(str, cell))} "
                   f"(of {len(data['elites'])} filled: {filled}{', ...' if len(data['elites']) > 8 else ''})")
