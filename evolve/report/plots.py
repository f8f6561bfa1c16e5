"""Fitness plots of run directories (PNG, matplotlib's Agg canvas: no display needed).

`plot_runs` compares methods: runs are grouped by every setting that makes them comparable
(evolve/report/groups.py: runs that differ in their seed alone), and each group becomes one curve,
the mean over seeds of the best fitness per generation, with a min..max band over seeds, so the
spread between seeds is visible rather than hidden in a mean. Each task gets its own row of
panels (tasks never share a y axis), with the species count and the body diversity (generations.csv's
n_species and body_diversity) beside the fitness where the runs record them.
`plot_runs(..., per_run=True)` draws one line per run instead. `plot_run` shows one run's best, mean
and median fitness. Generations are counted from 1 and the ticks are whole generations.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
import statistics
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from evolve.records.files import atomic_write
from evolve.records.rundir import champion_of, check_generation_numbers, generation_rows
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
    if not os.path.lexists(f):
        raise SgrError(f"{run_dir} has no generations.csv")
    try:
        rows, lines = generation_rows(f)  # a line being written (no newline yet) is no row
    except (csv.Error, UnicodeDecodeError) as exc:
        raise SgrError(f"{f}: not a readable CSV file ({exc})") from None
    if not rows:
        return {}
    if "generation" in rows[0]:
        check_generation_numbers(rows, lines, f)

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
    from evolve.report.groups import read_config

    run_dir = Path(run_dir)
    raw = read_config(run_dir)
    parent = run_dir.resolve().parent.name or UNKNOWN
    method = str(raw.get("method") or parent)
    if raw.get("layout") not in (None, "per_output"):  # the direct baseline's variant is its own group
        method = f"{method} ({raw['layout']})"
    if raw.get("robust"):  # scored by robust evaluation: another quantity, its own group
        method = f"{method} robust"
    shape = raw.get("robot_shape")
    if isinstance(shape, list) and len(shape) == 2 and list(shape) != [5, 5]:  # the paper's size unsaid
        method = f"{method} {shape[0]}x{shape[1]}"
    start = raw.get("start_from")
    if isinstance(start, dict):  # grown from another run's population: its own group
        method = f"{method} from g{start.get('generation', '?')}"
    return method, str(raw.get("task") or UNKNOWN)


def summarize_runs(run_dirs: Sequence[str | Path], column: str = "best",
                   pool: Sequence[str] = ()) -> dict[tuple[str, str], Curve]:
    """Group runs (evolve/report/groups.py: by every setting that makes them comparable, but those
    in `pool`), keyed (group label, task), and aggregate `column` per generation across runs.

    Runs may have different lengths (e.g. still running): each generation is aggregated over the
    runs that reached it. Runs with no rows, or without the column, are skipped.
    """
    from evolve.report.groups import group_of_each_run

    group_of = group_of_each_run([Path(d) for d in run_dirs], pool)
    groups: dict[tuple[str, str], list[dict[str, float]]] = {}
    for d in run_dirs:
        cols = read_generations(d)
        if not cols or column not in cols or "generation" not in cols:
            continue
        by_gen = {int(g): b for g, b in zip(cols["generation"], cols[column], strict=True)
                  if np.isfinite(g)}
        g = group_of[Path(d)]
        groups.setdefault((g.label, g.task), []).append(by_gen)
    curves = {}
    for (method, task), runs in sorted(groups.items()):
        gens = np.array(sorted(set().union(*runs)), dtype=np.int64)
        table = np.array([[r.get(int(g), np.nan) for g in gens] for r in runs])  # (runs, G)
        table = np.where(np.isfinite(table), table, np.nan)  # +-inf (no valid robot) counts as missing
        keep = ~np.all(np.isnan(table), axis=0)
        if not keep.any():  # an older run without the column's values
            continue
        t = table[:, keep]
        mean, low, high = np.nanmean(t, axis=0), np.nanmin(t, axis=0), np.nanmax(t, axis=0)
        curves[(method, task)] = Curve(method, task, gens[keep], mean, low, high, len(runs))
    return curves


# generations.csv's columns of diversity, drawn beside fitness where any run records them
DIVERSITY = {"n_species": "species",
             "body_diversity": "body diversity\n(mean pairwise distance per cell)"}


def diversity_columns(run_dirs: Sequence[str | Path]) -> list[str]:
    """The DIVERSITY columns with a finite value in any of the runs (older runs lack
    body_diversity; a method without bodies records NaN)."""
    found = []
    for column in DIVERSITY:
        for d in run_dirs:
            values = read_generations(d).get(column)
            if values is not None and np.isfinite(values).any():
                found.append(column)
                break
    return found


def draw_curves(ax: Axes, curves: dict[tuple[str, str], Curve],
                colors: dict[str, str] | None = None) -> list[Line2D]:
    """One line (mean best fitness) and one min..max band per group (in its colour of `colors`,
    by label, if given); returns the lines in key order."""
    lines = []
    for (method, task), c in curves.items():
        seeds = f"{c.n_runs} run{'s' if c.n_runs != 1 else ''}"
        (line,) = ax.plot(c.generation, c.mean, label=f"{method} / {task} (mean of {seeds}; band min-max)",
                          **({"color": colors[method]} if colors and method in colors else {}))
        ax.fill_between(c.generation, c.low, c.high, color=line.get_color(), alpha=0.2, linewidth=0)
        lines.append(line)
    return lines


def save_png(fig: Figure, out: str | Path, dpi: int = 120) -> Path:
    """Write the figure as a PNG of 256 colours, whole or not at all (made in memory, then
    `atomic_write`). A figure's few colours plus their anti-aliased edges fit a palette with no
    visible change, at about a third of the bytes of a true-colour PNG (reports are committed)."""
    from PIL import Image

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    image = Image.open(buf).convert("RGB")
    palette = image.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    small = io.BytesIO()
    palette.save(small, format="png", optimize=True)
    atomic_write(out, small.getvalue())
    return out


def plot_runs(run_dirs: Sequence[str | Path], out: str | Path, per_run: bool = False,
              pool: Sequence[str] = ()) -> Path:
    """PNG comparing groups of runs (`summarize_runs`), one row of panels per task (tasks never
    share a y axis): the mean best fitness per generation with a min..max band over seeds, or with
    `per_run` one line per run in its group's colour; beside it, where the runs record them,
    species and body diversity drawn the same way. Returns the PNG path."""
    from evolve.report.groups import run_settings

    curves = summarize_runs(run_dirs, pool=pool)
    if not curves:
        raise SgrError("no run with generations to plot among " + ", ".join(map(str, run_dirs)))
    tasks = sorted({t for _, t in curves})
    extra = diversity_columns(run_dirs)
    side_curves = {column: summarize_runs(run_dirs, column, pool) for column in extra}
    task_of = {Path(d): run_settings(Path(d))["task"] for d in run_dirs}
    colors = _group_colors(curves)
    fig = Figure(figsize=(8 + 4.5 * len(extra), 4.5 * len(tasks)))
    first = None
    for i, task in enumerate(tasks):
        ax = fig.add_subplot(len(tasks), 1 + len(extra), i * (1 + len(extra)) + 1)
        mine = [d for d in run_dirs if task_of[Path(d)] == task]
        if per_run:
            draw_runs(ax, mine, pool=pool, colors=colors)
        else:
            draw_curves(ax, {k: c for k, c in curves.items() if k[1] == task}, colors=colors)
        for j, column in enumerate(extra):
            side = fig.add_subplot(len(tasks), 1 + len(extra), i * (1 + len(extra)) + 2 + j)
            if per_run:
                draw_runs(side, mine, column, pool, colors, legend=False)
            else:
                draw_curves(side, {k: c for k, c in side_curves[column].items() if k[1] == task},
                            colors=colors)
            # the groups' colours are the fitness panel's: a legend here would only cover lines
            _style(side, f"{task}: {DIVERSITY[column].splitlines()[0]}", DIVERSITY[column], legend=False)
        if first is None:
            first = (ax, f"Best fitness per generation: {task}")
        else:
            _style(ax, f"Best fitness per generation: {task}", "best fitness")
    return _finish(fig, first[0], first[1], "best fitness", out)


def _group_colors(curves: dict[tuple[str, str], Curve]) -> dict[str, str]:
    """One colour per group label, the same in every panel."""
    cycle = iter(matplotlib_colors())
    return {label: next(cycle) for label in sorted({m for m, _ in curves})}


def draw_runs(ax: Axes, run_dirs: Sequence[str | Path], column: str = "best", pool: Sequence[str] = (),
              colors: dict[str, str] | None = None, legend: bool = True) -> None:
    """One line per run (`column` per generation), each run in its own shade of its group's colour,
    and (with `legend`) one legend entry per group.

    Args:
        ax: the panel.
        run_dirs: the runs.
        column: the generations.csv column drawn.
        pool: settings whose differences do not split groups (evolve/report/groups.py).
        colors: a colour per group label; groups not in it take the next of matplotlib's cycle.
        legend: draw the legend, one entry per group.
    """
    from matplotlib.lines import Line2D

    from evolve.report.groups import group_of_each_run

    group_of = group_of_each_run([Path(d) for d in run_dirs], pool)
    colors = dict(colors or {})
    cycle = iter(matplotlib_colors())
    drawn = [(Path(d), cols) for d in run_dirs
             if (cols := read_generations(d)) and column in cols and "generation" in cols]
    members: dict[str, list[Path]] = {}
    for d, _ in drawn:
        members.setdefault(group_of[d].label, []).append(d)
    for d, cols in drawn:
        g = group_of[d]
        if g.label not in colors:
            colors[g.label] = next(cycle)
        shade = run_shade(colors[g.label], members[g.label].index(d), len(members[g.label]))
        values = np.where(np.isfinite(cols[column]), cols[column], np.nan)
        ax.plot(cols["generation"], values, color=shade, alpha=0.9,
                label=f"_{g.label} / {g.task}: {d.name}")  # "_": no legend entry of its own
    if legend and members:
        ax.legend(handles=[Line2D([], [], color=colors[label], label=f"{label} ({len(runs)} run"
                                  f"{'s' if len(runs) != 1 else ''}, a shade each)")
                           for label, runs in members.items()], fontsize="small")


def run_shade(color: str, i: int, n: int) -> tuple[float, float, float]:
    """The `i`-th of `n` shades of `color`, from darker to lighter, `color` itself in the middle:
    the runs of one group told apart, the group still one hue."""
    from matplotlib.colors import to_rgb

    rgb = np.array(to_rgb(color))
    t = 0.0 if n == 1 else -0.45 + 0.9 * i / (n - 1)  # -0.45: towards black, +0.45: towards white
    mixed = rgb * (1 + t) if t < 0 else rgb + (1 - rgb) * t
    return tuple(float(x) for x in np.clip(mixed, 0, 1))


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


def plot_run(run_dir: str | Path, out: str | Path, diversity: bool = False) -> Path:
    """PNG of one run's best, mean and median fitness per generation, and its champion (of
    champion.json) as a star; with `diversity` (`sgr plot RUN`), beside it, where the run records
    them, its species count and body diversity (the run's own end file, fitness.png, keeps to
    fitness: its size is what the run's end budgets for). Returns the PNG path."""
    cols = read_generations(run_dir)
    if "generation" not in cols:
        raise SgrError(f"{run_dir}/generations.csv has no rows")
    method, task = run_labels(run_dir)
    extra = diversity_columns([run_dir]) if diversity else []
    # the diversity panels stacked small at the right: the PNG stays about the size it was
    fig = Figure(figsize=(8 + 2.5 * bool(extra), 4.5))
    grid = fig.add_gridspec(max(1, len(extra)), 2 if extra else 1, width_ratios=[2.4, 1] if extra else None)
    ax = fig.add_subplot(grid[:, 0])
    for name in ("best", "mean", "median"):
        if name in cols:
            ax.plot(cols["generation"], cols[name], label=name)
    champ = _champion(run_dir)
    if champ is not None:  # the champion of champion.json (re-chosen by select-champion: redrawn)
        ax.plot([champ[0]], [champ[1]], "k*", markersize=11,
                label=f"champion: {champ[1]:.3f} (generation {champ[0]})")
    for j, column in enumerate(extra):
        side = fig.add_subplot(grid[j, 1])
        side.plot(cols["generation"], np.where(np.isfinite(cols[column]), cols[column], np.nan))
        _style(side, DIVERSITY[column].splitlines()[0], "")
        if j < len(extra) - 1:
            side.set_xlabel("")
    return _finish(fig, ax, f"{method} / {task}: {Path(run_dir).name}", "fitness", out)


def _champion(run_dir: str | Path) -> tuple[int, float] | None:
    """(generation, fitness) of the run's champion.json, None without one (or a hand-made record
    without a generation); SgrError naming the file where it is damaged (`champion_of`)."""
    champ = champion_of(run_dir)
    gen = None if champ is None else champ.get("generation")
    if not isinstance(gen, int) or isinstance(gen, bool):
        return None
    return gen, float(champ["fitness"])


def _style(ax: Axes, title: str, ylabel: str, legend: bool = True) -> None:
    ax.set_title(title)
    ax.set_xlabel("generation")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # whole generations, never 2.5
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    if legend and any(not line.get_label().startswith("_") for line in ax.get_lines()):
        ax.legend(fontsize="small")


def _finish(fig: Figure, ax: Axes, title: str, ylabel: str, out: str | Path) -> Path:
    _style(ax, title, ylabel)
    fig.tight_layout()
    return save_png(fig, out)


def band(ax, curves: list[np.ndarray], color: str, label: str) -> None:
    """The mean over runs per generation (each run's values from generation 1) with a ± sd band;
    non-finite values count as missing."""
    n = max(len(c) for c in curves)
    table = np.full((len(curves), n), np.nan)
    for j, c in enumerate(curves):
        table[j, :len(c)] = np.where(np.isfinite(c), c, np.nan)
    seen = ~np.all(np.isnan(table), axis=0)
    if not seen.any():
        return
    g = np.arange(1, n + 1)[seen]
    t = table[:, seen]
    mean, sd = np.nanmean(t, axis=0), np.nanstd(t, axis=0)
    ax.plot(g, mean, color=color, label=label)
    ax.fill_between(g, mean - sd, mean + sd, color=color, alpha=0.2, linewidth=0)


def mean_sd(values: Sequence[float], digits: int = 2) -> str:
    """Mean ± sample sd of the finite values, "(n=k)" where some were not; one value alone has no sd
    (a report table's cell)."""
    v = [x for x in values if math.isfinite(x)]
    if not v:
        return "-"
    if len(v) == 1:  # "± 0.00" would read as a measured spread
        return f"{v[0]:.{digits}f}" + (" (n=1)" if len(values) != 1 else "")
    return (f"{statistics.fmean(v):.{digits}f} ± {statistics.stdev(v):.{digits}f}"
            + (f" (n={len(v)})" if len(v) != len(values) else ""))
