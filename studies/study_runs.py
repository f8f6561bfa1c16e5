"""What every study script does with its runs: run one to its end or resume it, tell whether it is
finished, and copy a finished run's records into the committed results folder.

A study is idempotent this way: a finished run is skipped, an unfinished one resumed
(`sgr evolve --resume`), so after a kill it goes on where it stood.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# a run's records: what a results folder keeps of it (its checkpoints and pictures stay behind)
RECORDS = ("config.yaml", "neat.ini", "generations.csv", "champion.json", "champion-best-ever.json")
# records no sgr command reads, kept gzipped (name + ".gz", no timestamp) to keep the tree small
GZIPPED = frozenset({"champion-best-ever.json"})
SGR = [sys.executable, "-m", "evolve.cli"]


def generations(run: Path) -> int:
    """The generations a run folder's config.yaml asks for (read as sgr reads it: `RunDir.config`)."""
    from evolve.records.rundir import RunDir

    return int(RunDir(run).config()["generations"])


def finished(run: Path) -> bool:
    """A run folder whose last checkpoint is its last generation and whose champion is written."""
    from evolve.records.rundir import RunDir

    if not (run / "config.yaml").is_file() or not (run / "champion.json").is_file():
        return False
    return RunDir(run).last_checkpoint_generation() == generations(run)


def evolve(run: Path, args: list[str], workers: int, to: int | None = None) -> None:
    """Run `sgr evolve ARGS --out RUN` to its end, or resume it; nothing when it is finished.

    With `to`, a run that exists is extended to that many generations (`--resume RUN --generations
    N`) unless it has them already."""
    if finished(run) and (to is None or generations(run) == to):
        return
    cmd = SGR + ["evolve", "--quiet", "--workers", str(workers)]
    cmd += ["--resume", str(run)] if (run / "config.yaml").is_file() else args + ["--out", str(run)]
    if to is not None and (run / "config.yaml").is_file():
        cmd += ["--generations", str(to)]
    print("+", " ".join(cmd[2:]), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)


def copy_record(source: Path, dest: Path, gzipped: bool | None = None) -> Path:
    """Copy one record file into the folder `dest`, gzipped (as NAME.gz, level 9, no timestamp)
    where `gzipped` says so, by default where its name is in GZIPPED; the copy."""
    import gzip

    if not (source.name in GZIPPED if gzipped is None else gzipped):
        return Path(shutil.copy2(source, dest / source.name))
    out = dest / (source.name + ".gz")
    out.write_bytes(gzip.compress(source.read_bytes(), 9, mtime=0))
    return out


def keep(run: Path, records: Path, names: tuple[str, ...] = RECORDS) -> None:
    """Copy a finished run's records (`names`, those it has) into the committed folder."""
    dest = records / run.name
    dest.mkdir(parents=True, exist_ok=True)
    for name in names:
        if (run / name).is_file():
            copy_record(run / name, dest)


def champion_grid(grid: list[list[tuple[Path, str]]], out: Path) -> Path:
    """One picture of many champion bodies: `grid` holds a row of (run folder, label) per picture
    row; each cell shows that run's champion body titled "label: fitness", blank where the run has
    no champion yet."""
    import json

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from evolve.report.gallery import body_image
    from evolve.report.plots import save_png

    n_cols = max(len(row) for row in grid)
    fig, axes = plt.subplots(len(grid), n_cols, figsize=(1.9 * n_cols, 1.9 * len(grid)), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for r, row in enumerate(grid):
        for c, (run, label) in enumerate(row):
            f = run / "champion.json"
            if f.is_file():
                rec = json.loads(f.read_text())
                axes[r][c].imshow(body_image(rec["body"], cell=8))
                axes[r][c].set_title(f"{label}: {rec['fitness']:.2f}", fontsize=6)
    fig.tight_layout()
    save_png(fig, out, dpi=110)
    plt.close(fig)
    return out
