"""Fitness plots of run directories (PNG, matplotlib's Agg canvas: no display needed).

`plot_runs` compares methods: runs are grouped by (method, task) from their config.yaml, and each
group becomes one curve, the mean over seeds of the best fitness per generation, with a min..max
band over seeds, so the spread between seeds is visible rather than hidden in a mean.
`plot_runs(..., per_run=True)` draws one line per run instead. `plot_run` shows one run's best, mean
and median fitness. Generations are counted from 1 and the ticks are whole generations.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from evolve.runs.files import atomic_write
from tsim.errors import SgrError

UNKNOWN = "unknown"
_WRAPPED = re.compile(r"^\s*[A-Za-z_][\w.]*\((.*)\)\s*$")


@dataclass(frozen=True)
class Curve:
    """Per-generation statistics of one (method, task) group across its runs (seeds)."""

    method: str
    task: str
    generation: np.ndarray  # (G,) generations present in at least one run
    mean: np.ndarray  # (G,) mean over runs of the best fitness
    low: np.ndarray  # (G,) min over runs
    high: np.ndarray  # (G,) max over runs
    n_runs: int


def read_generations(run_dir: str | Path) -> dict[str, np.ndarray]:
    """Columns of `run_dir/generations.csv` as float arrays (non-numeric cells become NaN);
    generations counted from 1, also in runs written when the file counted from 0."""
    f = Path(run_dir) / "generations.csv"
    if not f.is_file():
        raise SgrError(f"{run_dir} has no generations.csv")
    try:
        text = f.read_text()
        # a line being written (no newline yet) is no row
        rows = list(csv.DictReader(io.StringIO(text[:text.rfind("\n") + 1])))
    except (csv.Error, UnicodeDecodeError) as exc:
        raise SgrError(f"{f}: not a readable CSV file ({exc})") from None
    if not rows:
        return {}

    def num(v: str | None) -> float:
        m = _WRAPPED.match(v or "")  # numpy 2 reprs, e.g. "np.float64(1.5)"
        try:
            return float(m.group(1) if m else v)
        except (TypeError, ValueError):
            return float("nan")

    cols = {k: np.array([num(r.get(k)) for r in rows]) for k in rows[0]}
    if "generation" in cols and cols["generation"][0] == 0:  # written when rows counted from 0
        cols["generation"] = cols["generation"] + 1
    return cols


def run_labels(run_dir: str | Path) -> tuple[str, str]:
    """(method, task) of a run from its config.yaml; a missing method falls back to the name of the
    run directory's parent (runs are often stored as <experiment>/<seed>), a missing task to
    "unknown". Variants are their own method: "direct (per_cell)", "sgr robust" (robust
    evaluation), "sgr 10x10" (a body size other than the paper's 5x5), "sgr 10x10 from g50" (a run
    that started from another run's generation 50: `start_from`)."""
    run_dir = Path(run_dir)
    cfg: dict = {}
    f = run_dir / "config.yaml"
    if f.is_file():
        try:
            loaded = yaml.safe_load(f.read_text())
        except UnicodeDecodeError:
            raise SgrError(f"{f}: not a text file") from None
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            raise SgrError(f"{f}: not valid YAML{f' (line {mark.line + 1})' if mark else ''}") from None
        cfg = loaded if isinstance(loaded, dict) else {}
    parent = run_dir.resolve().parent.name or UNKNOWN
    method = str(cfg.get("method") or parent)
    if cfg.get("layout") not in (None, "per_output"):  # the direct baseline's variant is its own group
        method = f"{method} ({cfg['layout']})"
    if cfg.get("robust"):  # scored by robust evaluation: another quantity, its own group
        method = f"{method} robust"
    shape = cfg.get("robot_shape")
    if isinstance(shape, list) and len(shape) == 2 and list(shape) != [5, 5]:  # the paper's size unsaid
        method = f"{method} {shape[0]}x{shape[1]}"
    start = cfg.get("start_from")
    if isinstance(start, dict):  # grown from another run's population: its own group
        method = f"{method} from g{start.get('generation', '?')}"
    return method, str(cfg.get("task") or UNKNOWN)


def summarize_runs(run_dirs: Sequence[str | Path]) -> dict[tuple[str, str], Curve]:
    """Group runs by (method, task) and aggregate their best fitness per generation across runs.

    Runs may have different lengths (e.g. still running): each generation is aggregated over the
    runs that reached it. Runs with no rows are skipped.
    """
    groups: dict[tuple[str, str], list[dict[str, float]]] = {}
    for d in run_dirs:
        cols = read_generations(d)
        if not cols or "best" not in cols or "generation" not in cols:
            continue
        best_by_gen = {int(g): b for g, b in zip(cols["generation"], cols["best"], strict=True)
                       if np.isfinite(g)}
        groups.setdefault(run_labels(d), []).append(best_by_gen)
    curves = {}
    for (method, task), runs in sorted(groups.items()):
        gens = np.array(sorted(set().union(*runs)), dtype=np.int64)
        table = np.array([[r.get(int(g), np.nan) for g in gens] for r in runs])  # (runs, G)
        table = np.where(np.isfinite(table), table, np.nan)  # +-inf (no valid robot) counts as missing
        keep = ~np.all(np.isnan(table), axis=0)
        t = table[:, keep]
        mean, low, high = np.nanmean(t, axis=0), np.nanmin(t, axis=0), np.nanmax(t, axis=0)
        curves[(method, task)] = Curve(method, task, gens[keep], mean, low, high, len(runs))
    return curves


def draw_curves(ax: Axes, curves: dict[tuple[str, str], Curve]) -> list[Line2D]:
    """One line (mean best fitness) and one min..max band per group; returns the lines in key order."""
    lines = []
    for (method, task), c in curves.items():
        seeds = f"{c.n_runs} run{'s' if c.n_runs != 1 else ''}"
        (line,) = ax.plot(c.generation, c.mean, label=f"{method} / {task} (mean of {seeds}; band min-max)")
        ax.fill_between(c.generation, c.low, c.high, color=line.get_color(), alpha=0.2, linewidth=0)
        lines.append(line)
    return lines


def save_png(fig: Figure, out: str | Path, dpi: int = 120) -> Path:
    """Write the figure as a PNG, whole or not at all (made in memory, then `atomic_write`)."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    atomic_write(out, buf.getvalue())
    return out


def plot_runs(run_dirs: Sequence[str | Path], out: str | Path, per_run: bool = False) -> Path:
    """PNG comparing (method, task) groups of runs: mean best fitness per generation with a min..max
    band over seeds (`summarize_runs` gives the groups), or with `per_run` one line per run, in
    its group's colour. Returns the PNG path."""
    curves = summarize_runs(run_dirs)
    if not curves:
        raise SgrError("no run with generations to plot among " + ", ".join(map(str, run_dirs)))
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    if per_run:
        draw_runs(ax, run_dirs)
    else:
        draw_curves(ax, curves)
    tasks = sorted({t for _, t in curves})
    return _finish(fig, ax, f"Best fitness per generation: {', '.join(tasks)}", "best fitness", out)


def draw_runs(ax: Axes, run_dirs: Sequence[str | Path]) -> None:
    """One line per run (best fitness per generation), one colour per (method, task) group."""
    colors: dict[tuple[str, str], str] = {}
    cycle = iter(matplotlib_colors())
    for d in run_dirs:
        cols = read_generations(d)
        if not cols or "best" not in cols or "generation" not in cols:
            continue
        group = run_labels(d)
        if group not in colors:
            colors[group] = next(cycle)
        best = np.where(np.isfinite(cols["best"]), cols["best"], np.nan)
        ax.plot(cols["generation"], best, color=colors[group], alpha=0.85,
                label=f"{group[0]} / {group[1]}: {Path(d).name}")


def matplotlib_colors() -> list[str]:
    """matplotlib's default colour cycle, repeated (more groups than colours reuse them)."""
    from matplotlib import rcParams

    return rcParams["axes.prop_cycle"].by_key()["color"] * 8


def runs_plot_path(run_dirs: Sequence[str | Path]) -> Path:
    """Where `sgr plot` puts a plot of several runs (or of one with --per-run or --compare) without
    --out: fitness.png in the folder that holds them all (runs/fitness.png for runs/*), never in the
    working folder; fitness-runs.png inside a run directory given alone (its fitness.png is the
    run's own plot)."""
    common = Path(os.path.commonpath([Path(d).resolve() for d in run_dirs]))
    if len(run_dirs) == 1 or (common / "generations.csv").is_file():
        return common / "fitness-runs.png"
    return common / "fitness.png"


def plot_run(run_dir: str | Path, out: str | Path) -> Path:
    """PNG of one run's best, mean and median fitness per generation, and its champion (of
    champion.json) as a star; returns the PNG path."""
    cols = read_generations(run_dir)
    if "generation" not in cols:
        raise SgrError(f"{run_dir}/generations.csv has no rows")
    method, task = run_labels(run_dir)
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    for name in ("best", "mean", "median"):
        if name in cols:
            ax.plot(cols["generation"], cols[name], label=name)
    champ = _champion(run_dir)
    if champ is not None:  # the champion of champion.json (re-chosen by select-champion: redrawn)
        ax.plot([champ[0]], [champ[1]], "k*", markersize=11,
                label=f"champion: {champ[1]:.3f} (generation {champ[0]})")
    return _finish(fig, ax, f"{method} / {task}: {Path(run_dir).name}", "fitness", out)


def _champion(run_dir: str | Path) -> tuple[int, float] | None:
    """(generation, fitness) of the run's champion.json, None without a readable one."""
    try:
        champ = json.loads((Path(run_dir) / "champion.json").read_text())
        return int(champ["generation"]), float(champ["fitness"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _finish(fig: Figure, ax: Axes, title: str, ylabel: str, out: str | Path) -> Path:
    ax.set_title(title)
    ax.set_xlabel("generation")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # whole generations, never 2.5
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    return save_png(fig, out)
