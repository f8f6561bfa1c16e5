"""Run directories: resolved config, per-generation CSV, champion JSON, atomic checkpoints.

Layout: config.yaml, neat.ini (the INI actually used), generations.csv, champion.json,
checkpoints/gen-XXXXX.pkl (state at the start of generation XXXXX). Every file that a crash could
leave half-written is written to a temporary file and renamed over the old one.
"""

from __future__ import annotations

import csv
import io
import json
import os
import pickle
import tempfile
from pathlib import Path

import yaml

COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes",
           "build_s", "sim_s", "neat_s", "total_s"]
KEEP_CHECKPOINTS = 2


def atomic_write(path: Path, data: bytes) -> None:
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class RunDir:
    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.ckpt_dir = self.path / "checkpoints"

    # ------------------------------------------------------------------ creation
    def create(self, cfg: dict, neat_ini: str, extra_files: dict[str, str] | None = None) -> None:
        if (self.path / "generations.csv").exists():
            raise ValueError(f"run directory {self.path} already holds a run; use --resume {self.path} "
                             "or another --out")
        self.ckpt_dir.mkdir(parents=True, exist_ok=True)
        atomic_write(self.path / "config.yaml", yaml.safe_dump(cfg, sort_keys=False).encode())
        atomic_write(self.path / "neat.ini", neat_ini.encode())
        for name, text in (extra_files or {}).items():
            atomic_write(self.path / name, text.encode())
        self._write_rows([])

    def config(self) -> dict:
        f = self.path / "config.yaml"
        if not f.is_file():
            raise ValueError(f"{self.path} is not a run directory (no config.yaml)")
        return yaml.safe_load(f.read_text())

    # ------------------------------------------------------------------ generations.csv
    def rows(self) -> list[dict]:
        f = self.path / "generations.csv"
        if not f.is_file():
            return []
        with f.open() as fh:
            return list(csv.DictReader(fh))

    def _write_rows(self, rows: list[dict]) -> None:
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: r[k] for k in COLUMNS})
        atomic_write(self.path / "generations.csv", buf.getvalue().encode())

    def append_row(self, row: dict) -> None:
        rows = self.rows()
        rows.append({k: (repr(float(v)) if isinstance(v, float) else v) for k, v in row.items()})
        self._write_rows(rows)

    def truncate_rows(self, generation: int) -> None:
        """Drop rows of generations >= `generation` (they are recomputed after a resume)."""
        self._write_rows([r for r in self.rows() if int(r["generation"]) < generation])

    # ------------------------------------------------------------------ champion, checkpoints
    def write_champion(self, champion: dict) -> None:
        atomic_write(self.path / "champion.json", json.dumps(champion, indent=1).encode())

    def champion(self) -> dict:
        f = self.path / "champion.json"
        if not f.is_file():
            raise ValueError(f"{self.path} has no champion.json yet")
        return json.loads(f.read_text())

    def save_checkpoint(self, generation: int, state: dict) -> Path:
        self.ckpt_dir.mkdir(parents=True, exist_ok=True)
        path = self.ckpt_dir / f"gen-{generation:05d}.pkl"
        atomic_write(path, pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL))
        for old in sorted(self.ckpt_dir.glob("gen-*.pkl"))[:-KEEP_CHECKPOINTS]:
            old.unlink()
        return path

    def latest_checkpoint(self) -> dict | None:
        ckpts = sorted(self.ckpt_dir.glob("gen-*.pkl"))
        if not ckpts:
            return None
        return pickle.loads(ckpts[-1].read_bytes())
