"""Where each part of a run's life ran: segments.json in the run folder, one entry per start or
resume (the generation it started after, the arch it ran on, the device, the precision, the
rollout workers, when). A run started for CUDA and resumed on the CPU says so here; config.yaml
holds the run's config only (an older sgr wrote the creating arch there: `segments` reads it as
the first segment, and the first resume moves it here).

`segments(run)` and `backend_summary(run)` are what reports call; reading is plain JSON.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import yaml

from evolve.records.files import atomic_write, load_yaml
from tsim.backend import DEFAULT_PRECISION
from tsim.files import CONFIG_CAP, read_text

SEGMENTS_FILE = "segments.json"


def segments(run: str | Path) -> list[dict]:
    """The run's segments, oldest first: each {"after_generation", "arch", "device", "software",
    "precision", "workers", "started"} (an older run's first: only what its config.yaml held);
    [] when nothing was recorded."""
    path = Path(run) / SEGMENTS_FILE
    if path.is_file():
        try:
            data = json.loads(read_text(path, CONFIG_CAP))
        except (OSError, ValueError):  # SgrError: a FIFO, a link, too large
            return []
        return [s for s in data if isinstance(s, dict)] if isinstance(data, list) else []
    try:
        raw = load_yaml(read_text(Path(run) / "config.yaml", CONFIG_CAP))
    except (OSError, ValueError, yaml.YAMLError):
        return []
    if isinstance(raw, dict) and isinstance(raw.get("arch"), str):  # an older sgr's record
        return [{"after_generation": 0, "arch": raw["arch"], "device": None, "software": None,
                 "precision": raw.get("precision") or DEFAULT_PRECISION, "workers": raw.get("workers"),
                 "started": None}]
    return []


def record_segment(run: str | Path, after_generation: int, backend: dict, workers: int | str) -> list[dict]:
    """Append the segment that starts now, after `after_generation` generations, on `backend`
    (`tsim.backend.Backend.record()`); an older run's config.yaml `arch` moves into the file.
    Returns every segment."""
    run = Path(run)
    found = segments(run)
    entry = {"after_generation": after_generation, "arch": backend["arch"], "device": backend["device"],
             "software": backend["software"], "precision": backend["precision"], "workers": workers,
             "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    if backend.get("asked") not in (None, backend["arch"]):
        entry["asked"] = backend["asked"]  # e.g. "gpu"
    found.append(entry)
    atomic_write(run / SEGMENTS_FILE, (json.dumps(found, indent=1) + "\n").encode(), inside=run)
    cfg_file = run / "config.yaml"
    raw = load_yaml(read_text(cfg_file, CONFIG_CAP))
    if isinstance(raw, dict) and "arch" in raw:  # recorded above now, where it stays true
        atomic_write(cfg_file, yaml.safe_dump({k: v for k, v in raw.items() if k != "arch"},
                                              sort_keys=False).encode(), inside=run)
    return found


def backend_summary(run: str | Path) -> str:
    """A run's backends in a few words, for a report's table: "cpu, f64"; "cuda, then cpu from
    generation 3, f64"; "" when nothing was recorded."""
    parts, last = [], None
    found = segments(run)
    for s in found:
        arch = str(s.get("arch"))
        if last is None:
            parts.append(arch)
        elif arch != last:
            parts.append(f"then {arch} from generation {int(s.get('after_generation') or 0) + 1}")
        last = arch
    if not parts:
        return ""
    return ", ".join(parts + ["/".join(dict.fromkeys(str(s.get("precision")) for s in found))])
