"""The report's quality-diversity figures: each map-elites run's coverage, QD score and best elite
(summary.csv's QD_COLUMNS, report.md's "Quality diversity" table, qd-curves.png), and what every
champion does (its behaviour features, tasks/behaviour.py: summary.csv's BEHAVIOUR_COLUMNS and
report.md's "What the champions do").
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from evolve.report.plots import mean_sd
from evolve.report.sections import Section, SectionPart, register_section
from tasks.behaviour import FEATURES

# summary.csv's columns of a map-elites run's archive at its last generation: its coverage, QD score
# (evolve/methods/map_elites.py `qd_score`), elites, best elite's recorded fitness, the QD score's
# offset and the descriptors ("actuator x rigid")
QD_COLUMNS = ("coverage", "qd_score", "n_elites", "best_elite", "score_offset", "descriptors")
# summary.csv's columns of the champion's behaviour: the mean of each feature over the episodes its
# fitness scores (`evolve.records.replay.champion_behaviour`), where the report replayed champions
BEHAVIOUR_COLUMNS = tuple(f"behaviour_{f}" for f in FEATURES)


def qd_row(run_dir: Path, cols: dict[str, np.ndarray]) -> dict:
    """A run's QD_COLUMNS: its last generation's coverage and QD score (generations.csv), its
    archive's elites and best elite, offset and descriptors (elites.json); {} for a run without an
    archive."""
    from evolve.records.elites import elites_file, read_elites

    if elites_file(run_dir) is None or "coverage" not in cols or not len(cols["coverage"]):
        return {}
    data = read_elites(run_dir)
    fits = [float(e["champion"]["fitness"]) for e in data["elites"]]
    out = {"coverage": float(cols["coverage"][-1]), "qd_score": float(cols["qd_score"][-1]),
           "n_elites": len(fits), "best_elite": max(fits) if fits else math.nan,
           "descriptors": " x ".join(data["descriptors"])}
    if isinstance(data.get("score_offset"), int | float):
        out["score_offset"] = float(data["score_offset"])
    return out


def behaviour_row(run_dir: Path) -> dict:
    """A champion's BEHAVIOUR_COLUMNS (`champion_behaviour`: replayed from champion.json); {} where
    sgr cannot replay it (a method of the user's own controller format)."""
    from evolve.records.replay import champion_behaviour
    from tsim.errors import SgrError

    try:
        features = champion_behaviour(run_dir)
    except SgrError:
        return {}
    return {f"behaviour_{k}": v for k, v in features.items()}


def qd_markdown(rows: list[dict]) -> str:
    """report.md's "Quality diversity": per (group, task) of map-elites runs, mean ± sd over seeds of
    the coverage, QD score and best elite at the last generation, with the descriptors and offset;
    "" when no run keeps an archive."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in rows:
        if "coverage" in r:
            groups[(r["method"], r["task"])].append(r)
    if not groups:
        return ""
    lines = ["", "## Quality diversity", "",
             "Each map-elites group at its runs' last generation (mean ± sd over seeds): the share of the "
             "archive's cells filled, the QD score (the sum over elites of max(0, fitness - offset); "
             "the offset is the task's floor unless the config set it, evolve/methods/qd_floors.py), and "
             "the best elite's recorded fitness. qd-curves.png draws them per generation.", "",
             "| method | task | runs | descriptors | offset | coverage | QD score | elites | best elite |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (method, task), rs in sorted(groups.items()):
        desc = sorted({str(r.get("descriptors", "")) for r in rs})
        offs = sorted({r["score_offset"] for r in rs if "score_offset" in r})
        coverage, score = mean_sd([100 * r["coverage"] for r in rs], 1), mean_sd([r["qd_score"] for r in rs])
        elites, best = mean_sd([r["n_elites"] for r in rs], 0), mean_sd([r["best_elite"] for r in rs])
        offset = ", ".join(f"{o:g}" for o in offs) or "-"
        lines.append(f"| {method} | {task} | {len(rs)} | {', '.join(desc)} | {offset} | {coverage} % | "
                     f"{score} | {elites} | {best} |")
    return "\n".join(lines) + "\n"


def behaviour_markdown(rows: list[dict]) -> str:
    """report.md's "What the champions do": each replayed champion's behaviour features; "" when the
    report replayed none."""
    have = [r for r in rows if BEHAVIOUR_COLUMNS[0] in r]
    if not have:
        return ""
    lines = ["", "## What the champions do", "",
             "Each champion's behaviour (tasks/behaviour.py), the mean over the episodes its fitness "
             "scores: the COM's net displacement and its height above the start (voxels), the "
             "actuation's dominant frequency (Hz of simulated time), the share of steps touching the "
             "terrain, and the final orientation (radians).", "",
             "| run | " + " | ".join(FEATURES) + " |", "|---" * (1 + len(FEATURES)) + "|"]
    for r in sorted(have, key=lambda r: r["run"]):
        lines.append(f"| {r['run']} | " + " | ".join(f"{r[c]:.2f}" for c in BEHAVIOUR_COLUMNS) + " |")
    return "\n".join(lines) + "\n"


def qd_curves_html(path: Path | None) -> list[str]:
    """report.html's QD curves, the image inlined; [] without them."""
    if path is None:
        return []
    from evolve.report.gallery import data_uri

    return [f"<img alt='QD curves' src='{data_uri(path)}' width='100%'>"]


def plot_qd_curves(runs: list[Path], path: Path, pool: Sequence[str] = ()) -> Path | None:
    """qd-curves.png: per task, the coverage and the QD score per generation of each group of
    map-elites runs (mean ± sd over seeds); None (and no file) when no run records them."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from evolve.records.elites import elites_file
    from evolve.report.groups import group_of_each_run
    from evolve.report.plots import band, matplotlib_colors, read_generations, save_png

    with_archive = [d for d in runs if elites_file(d) is not None]
    if not with_archive:
        return None
    group_of = group_of_each_run(with_archive, pool)
    series: dict[str, dict[str, dict[str, list[np.ndarray]]]] = defaultdict(
        lambda: defaultdict(lambda: defaultdict(list)))
    for d in with_archive:
        cols = read_generations(d)
        g = group_of[d]
        for key in ("coverage", "qd_score"):
            if key in cols and len(cols[key]):
                series[g.task][g.label][key].append(cols[key] * (100.0 if key == "coverage" else 1.0))
    if not series:
        return None
    tasks = sorted(series)
    fig = Figure(figsize=(12, 3.6 * len(tasks)))
    FigureCanvasAgg(fig)
    cycle = matplotlib_colors()
    labels = sorted({m for t in series.values() for m in t})
    color = {m: cycle[i % len(cycle)] for i, m in enumerate(labels)}
    for i, task in enumerate(tasks):
        for j, (key, ylabel) in enumerate((("coverage", "coverage (% of cells)"), ("qd_score", "QD score"))):
            ax = fig.add_subplot(len(tasks), 2, 2 * i + j + 1)
            for method, s in sorted(series[task].items()):
                if s[key]:
                    band(ax, s[key], color[method], f"{method} ({len(s[key])} seeds)")
            ax.set_title(f"{task}: {ylabel}")
            ax.set_xlabel("generation")
            ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
            if ax.get_lines():
                ax.legend(fontsize="small")
    fig.tight_layout()
    return save_png(fig, path, dpi=110)


def _qd_part(rows: list[dict], runs: list[Path], folder: Path, pool: Sequence[str]) -> SectionPart:
    """The "Quality diversity" table, and in report.html qd-curves.png under it."""
    from evolve.report.gallery import markdown_html

    text = qd_markdown(rows)
    curves = plot_qd_curves(runs, folder / "qd-curves.png", pool) if text else None
    if curves is None:
        return SectionPart(text)
    return SectionPart(text + "\nqd-curves.png: the coverage and QD score per generation.\n",
                       [markdown_html(text), *qd_curves_html(curves)])


def _behaviour_row(run_dir: Path, cols: dict[str, np.ndarray], replayed: bool) -> dict:
    return behaviour_row(run_dir) if replayed else {}


register_section(Section("quality diversity", QD_COLUMNS, lambda d, cols, replayed: qd_row(d, cols),
                         _qd_part, order=10))
register_section(Section("behaviour", BEHAVIOUR_COLUMNS, _behaviour_row,
                         lambda rows, runs, folder, pool: SectionPart(behaviour_markdown(rows)), order=20))
