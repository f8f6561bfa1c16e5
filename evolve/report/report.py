"""A sweep's results as a table, a CSV and a figure, with the SGR authors' figures beside ours.

`sgr report DIR` reads every run directory at any depth below DIR (a sweep, a folder of runs or of
sweeps) and writes report.md, summary.csv and curves.png; what it passes over (files, a decoded
champion, half a run) it names, with why. Runs are averaged only when they differ in their seed
alone (evolve/report/groups.py; `--pool` averages across the settings it names), and report.md lists
the groups with their settings and runs. Between methods on a task (every other setting equal), a
two-sided Mann-Whitney U test on the runs' champion fitness gives a p-value and the Vargha-Delaney
A12. "Best at generation g" is the best fitness found in generations 1..g (1-based; generation 1 is
the first evaluated population), the quantity the paper's curves plot.

Robustness: evolution in a chaotic simulator can select a lucky trajectory, so each champion is
replayed from its champion.json at each noise level eps (default 1e-9, rounding, and 1e-3, a
physical actuator's error) with uniform(+-eps) added to every action, a different draw per replay;
the report gives the mean, sd and min of those returns beside the champion's recorded fitness and
its nominal (unperturbed) return. A champion whose return collapses under a 1e-9 change of its
actions has found a knife-edge trajectory, not a gait. `replay` is the recorded fitness scored
again from champion.json alone (for runs with robust evaluation, over the same perturbed episodes
as in evolution): it must equal `champion_fitness`.
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import os
from collections import defaultdict
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from evolve.records import verdict as verdict_rule
from evolve.records.files import atomic_write, load_yaml
from evolve.records.rundir import champion_of
from evolve.records.segments import backend_summary
from evolve.report import archive as _archive  # noqa: F401 (registers the archives section)
from evolve.report import champions as _champions  # noqa: F401 (registers bodies and backends)
from evolve.report import qd as _qd  # noqa: F401 (registers quality diversity and behaviour)
from evolve.report.gallery import champion_figure
from evolve.report.groups import episode_length
from evolve.report.plots import band, mean_sd, read_generations, save_png
from evolve.report.sections import SECTIONS
from tsim.errors import SgrError
from tsim.files import CONFIG_CAP, read_text

CHECKPOINTS = (1, 30, 100)  # 1-based generations reported, plus the end
# The authors' released logs (fhtanaka/SGR), mean best at generation 1 (their 0), 30, 100, end.
AUTHORS: dict[tuple[str, str], tuple[float | str | None, ...]] = {
    ("sgr", "Walker-v0"): (5.75, 6.09, 6.56, 6.60),
    ("sgr", "ObstacleTraverser-v1"): (3.01, 7.53, 7.57, 7.57),
    ("sgr", "Climber-v2"): (0.46, 0.90, 1.04, 1.08),
    ("sgr", "Thrower-v0"): (1.22, 1.94, 3.16, 3.50),
    # their "direct NEAT" logs are almost certainly SGR runs (docs/RESULTS.md): end values only
    ("direct", "Walker-v0"): (None, None, None, 6.70),
    ("direct", "ObstacleTraverser-v1"): (None, None, None, 7.57),
    ("direct", "Climber-v2"): (None, None, None, 1.10),
    ("direct", "Thrower-v0"): (None, None, None, 3.45),
    ("nested", "ObstacleTraverser-v1"): (1.14, None, None, "2.5-3.2"),  # end: range over their seeds
}
AUTHORS_GENERATIONS = 100  # their "end" figures come from runs of at least this many generations


def authors_not_comparable(task: str, episode_steps: list) -> str | None:
    """Why the authors' figures for `task` cannot be set beside runs with these episode lengths
    (they ran the paper's), or None when they can."""
    from tasks.specs import TASKS

    theirs = TASKS[task].paper_steps if task in TASKS else None
    ours = sorted({s for s in episode_steps if s is not None})
    if theirs is None or ours == [theirs]:
        return None
    return (f"not comparable: {'/'.join(map(str, ours)) or '?'}-step episodes, theirs {theirs}")


SUMMARY_COLUMNS = ["method", "task", "seed", "generations", "best_gen1", "best_gen30", "best_gen100",
                   "best_final", "champion_fitness", "headline", "headline_sd", "headline_verdict", "replay",
                   "nominal", "s_per_gen", "run"]
NOISE_LEVELS = (1e-9, 1e-3)  # sgr report's default: rounding, and a physical actuator's error
NOISE_STATS = ("mean", "sd", "min", "ratio")  # ratio: mean / nominal (NaN unless nominal > 0)


def noise_column(eps: float, stat: str) -> str:
    """summary.csv's column of `stat` over the replays at noise level eps, e.g. noise1e-09_mean."""
    return f"noise{eps:.0e}_{stat}"


def summary_columns(levels: Sequence[float] = NOISE_LEVELS) -> list[str]:
    """summary.csv's columns: SUMMARY_COLUMNS, then each level's NOISE_STATS before `run`."""
    noise = [noise_column(e, s) for e in levels for s in NOISE_STATS]
    return SUMMARY_COLUMNS[:-2] + noise + SUMMARY_COLUMNS[-2:]


def find_report_runs(folders: Sequence[str | Path]) -> tuple[list[Path], list]:
    """The run folders (config.yaml and generations.csv) at any depth below `folders` (each may
    be a run itself, as `sgr render RUN` takes it) and what was skipped, with why
    (evolve/report/groups.py); SgrError when there is no run at all."""
    from evolve.report.groups import find_runs

    runs, skipped = find_runs(folders)
    if not runs:
        raise SgrError(f"{', '.join(map(str, folders))} holds no run directories (folders with config.yaml "
                       "and generations.csv)" + "".join(f"; {s.line()}" for s in skipped[:5]))
    return runs, skipped


def run_names(runs: Sequence[Path]) -> dict[Path, str]:
    """Each run's name in the report: its path below the folder that holds them all (the folder's
    name for runs side by side, as sweeps lay them out; a longer path where runs sit at several
    depths or in several folders, so that no two share a name)."""
    if not runs:
        return {}
    base = Path(os.path.commonpath([Path(d).resolve().parent for d in runs]))
    return {d: Path(d).resolve().relative_to(base).as_posix() for d in runs}


def best_so_far(cols: dict[str, np.ndarray]) -> np.ndarray:
    """(G,) best fitness of generations 1..g for each g of a run's columns (`read_generations`;
    non-finite bests count as -inf); empty when the run has no rows."""
    best = cols.get("best", np.zeros(0))
    best = np.where(np.isfinite(best), best, -np.inf)
    return np.maximum.accumulate(best) if len(best) else best


def champion_robustness(run_dir: Path, replays: int = 10,
                        levels: Sequence[float] = NOISE_LEVELS) -> dict:
    """The champion's recorded fitness, that fitness scored again from champion.json (`replay`),
    its nominal return, and per noise level the mean, sd, min and mean / nominal of `replays`
    episodes with uniform(-eps, eps) added to every action (each level one batch)."""
    from evolve.records.replay import replay_champion, rescore_champion
    from evolve.records.rundir import RunDir

    champ = RunDir(run_dir).champion()
    out = {"champion_fitness": float(champ["fitness"]), "replay": rescore_champion(run_dir),
           "replays": replays}
    for eps in levels:
        total = replay_champion(run_dir, replays, eps)
        nominal, perturbed = float(total[0]), total[1:]
        out["nominal"] = nominal
        mean = float(perturbed.mean())
        out.update({noise_column(eps, "mean"): mean, noise_column(eps, "sd"): float(perturbed.std()),
                    noise_column(eps, "min"): float(perturbed.min()),
                    noise_column(eps, "ratio"): mean / nominal if nominal > 0 else math.nan})
    return out


def summarize(runs: list[Path], robustness: bool = True, levels: Sequence[float] = NOISE_LEVELS,
              replays: int = 10, pool: Sequence[str] = ()) -> list[dict]:
    """One row per run (`summary_columns`): its group's label as `method` (evolve/report/groups.py:
    runs that differ in their seed alone, or in the settings in `pool`) and its `settings`; best
    so far at generations 1, 30, 100 and the end (NaN when not reached); the champion's recorded
    fitness; `robustness` also replays each champion (`champion_robustness`)."""
    from evolve.report.groups import group_of_each_run

    group_of = group_of_each_run(runs, pool)
    names = run_names(runs)
    champions = {d: champion_of(d) for d in runs}  # every damaged file is found before any replay
    generations = {d: read_generations(d) for d in runs}
    rows = []
    for d in runs:
        g = group_of[d]
        raw = load_yaml(read_text(d / "config.yaml", CONFIG_CAP)) or {}
        cols = generations[d]
        best = best_so_far(cols)
        row = {"method": g.label, "task": g.task, "seed": raw.get("seed"), "generations": len(best),
               "run": names[d], "s_per_gen": (float(np.median(cols["total_s"])) if len(best) else math.nan),
               "episode_steps": episode_length(raw, g.task), "settings": g.settings, "classic": g.classic,
               "path": d, "backend": backend_summary(d)}
        champ = champions[d]
        if champ is not None:
            row["champion_fitness"] = float(champ["fitness"])
            h = verdict_rule.from_headline(champ.get("headline"))
            if h is not None:  # the one figure (evolve/records/verdict.py), as the run's end recorded it
                row.update(headline=h.noisy_mean, headline_sd=h.sd, headline_verdict=h.label)
            row.update(champion_body_measures(champ))
        diversity = cols.get("body_diversity", np.zeros(0))  # older runs: no column
        if len(diversity) and math.isfinite(diversity[-1]):
            row["body_diversity"] = float(diversity[-1])
        for g in CHECKPOINTS:
            row[f"best_gen{g}"] = float(best[g - 1]) if len(best) >= g else math.nan
        row["best_final"] = float(best[-1]) if len(best) else math.nan
        replayed = robustness and (d / "champion.json").is_file()
        if replayed:
            row.update(champion_robustness(d, replays, levels))
            if verdict_rule.EPS in levels:  # the gallery's caption says it too
                row["verdict"] = row.get("headline_verdict") or _verdict(row).label
        for section in SECTIONS.values():  # (evolve/report/sections.py)
            if section.row is not None:
                row.update(section.row(d, cols, replayed))
        rows.append(row)
    return rows


def champion_body_measures(champ: dict) -> dict[str, float]:
    """The measures of a champion record's body (evolve/methods/body_measures.py) that summary.csv
    keeps (BODY_COLUMNS); {} without a body."""
    from evolve.methods.body_measures import measures

    if "body" not in champ:
        return {}
    m = measures(np.asarray(champ["body"], dtype=np.int64))
    return {k: m[k] for k in BODY_COLUMNS if k in m}


def _levels(rows: list[dict]) -> list[float]:
    """The noise levels the rows were replayed at, in column order."""
    out: list[float] = []
    for r in rows:
        for k in r:
            if k.startswith("noise") and k.endswith("_mean"):
                eps = float(k[len("noise"):-len("_mean")])
                if eps not in out:
                    out.append(eps)
    return out


def _runs_and_seeds(rs: list[dict]) -> str:
    """The runs of a row and their seeds: "1 (seed 0)", "3 (seeds 0, 1, 2)" (a bare "0" read as
    zero seeds)."""
    seeds = ", ".join(str(r["seed"]) for r in rs)
    return f"{len(rs)} (seed{'s' if len(rs) != 1 else ''} {seeds})"


def _fmt(x: float | str | None) -> str:
    return "-" if x is None else x if isinstance(x, str) else f"{x:.2f}"


def report_markdown(rows: list[dict], skipped: Sequence = (), pool: Sequence[str] = ()) -> str:
    """report.md's text: `summarize` rows grouped by (method, task) (`method` is the group's label:
    evolve/report/groups.py), mean +- sd over seeds, with the authors' figures beside; the groups and
    their settings; Mann-Whitney U tests between methods (`method_tests`); each champion under
    noise, run by run; the paths `skipped` (evolve/report/groups.py's Skipped), with why."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in rows:
        groups[(r["method"], r["task"])].append(r)
    levels = _levels(rows)
    out = io.StringIO()
    out.write("# Results\n\nBest fitness found up to generation g (mean ± sd over seeds); "
              "*authors*: the SGR authors' released logs. *champion*: its headline, the mean return "
              "of episodes that took no part in choosing it, under the run's noise (champion.json's "
              "`headline`; `sgr explain RUN` says what each figure is; a record without one: its recorded "
              "fitness); *hold*: how many champions' verdicts say holds; "
              "*nominal*: its return replayed without noise (the same, unless the run was scored "
              "by robust evaluation); *±eps*: the champion replayed with uniform(±eps) added to "
              "every action (mean over replays, then mean ± sd over seeds; *worst*: the worst "
              "replay of any seed).")
    if any(method.endswith("robust") for method, _ in groups):
        out.write(" For runs scored by robust evaluation (*... robust*) the generation columns are "
                  "the best of noisy scores, which selection biases upward; their *champion* is the "
                  "headline of the champion file, scored afresh where the run chose it by "
                  "final selection (docs/EVOLVE.md).")
    out.write("\n\n")
    judged = verdict_rule.EPS in levels  # the verdict's column: how many champions hold
    noise_head = "".join(f" ±{e:g} | worst ±{e:g} |" for e in levels) + (" hold |" if judged else "")
    # a generation's column where some run reached it; the authors' only beside the paper's tasks
    gen_cols = [g for g in CHECKPOINTS if g == 1 or any(int(r["generations"]) >= g for r in rows)]
    with_authors = any(AUTHORS.get((rs[0].get("classic", m), t)) for (m, t), rs in groups.items())
    out.write("| method | task | runs (seeds) | generations | " + "".join(f"gen {g} | " for g in gen_cols)
              + "end | " + ("authors (1 / 30 / 100 / end) | " if with_authors else "")
              + f"champion | nominal |{noise_head}\n")
    out.write("|---" * (7 + len(gen_cols) + with_authors + 2 * len(levels) + judged) + "|\n")
    for (method, task), rs in sorted(groups.items()):
        gens = sorted({r["generations"] for r in rs})
        authors = AUTHORS.get((rs[0].get("classic", method), task))
        a = " / ".join(_fmt(x) for x in authors) if authors else "-"
        why = authors_not_comparable(task, [r.get("episode_steps") for r in rs]) if authors else None
        if why:  # another episode length: their figures measure something else
            a = f"{a} ({why})"
        elif authors and max(gens) < AUTHORS_GENERATIONS:  # only the generations these runs reached
            shown = [x if g <= max(gens) else None for x, g in zip(authors, CHECKPOINTS, strict=False)]
            a = " / ".join(_fmt(x) for x in [*shown, None])
        rob = [r for r in rs if "nominal" in r]
        cells = [mean_sd([champion_figure(r) for r in rob]) if rob else "-",
                 mean_sd([r["nominal"] for r in rob]) if rob else "-"]
        for e in levels:
            have = [r for r in rob if noise_column(e, "mean") in r]
            cells.append(mean_sd([r[noise_column(e, "mean")] for r in have]) if have else "-")
            cells.append(f"{min(r[noise_column(e, 'min')] for r in have):.2f}" if have else "-")
        if judged:
            have = [r for r in rob if noise_column(verdict_rule.EPS, "mean") in r]
            cells.append(f"{sum(_holds(r) for r in have)} of {len(have)}" if have else "-")
        out.write(f"| {method} | {task} | {_runs_and_seeds(rs)} | "
                  f"{gens[0] if len(gens) == 1 else f'{gens[0]}-{gens[-1]}'} | "
                  + "".join(mean_sd([r[f"best_gen{g}"] for r in rs]) + " | " for g in gen_cols)
                  + f"{mean_sd([r['best_final'] for r in rs])} | " + (f"{a} | " if with_authors else "")
                  + " | ".join(cells) + " |\n")
    off = [r for r in rows if "replay" in r and abs(r["replay"] - r["champion_fitness"]) > 1e-9]
    if off:  # champion.json alone must reproduce the fitness; say plainly where it does not
        out.write(f"\n**{len(off)} of {sum('replay' in r for r in rows)} champions do not replay to "
                  "their recorded fitness** from champion.json (> 1e-9): "
                  + "; ".join(f"{r['run']} {r['champion_fitness']:.6g} -> {r['replay']:.6g}"
                              for r in off) + ".\n")
    out.write(groups_markdown(rows, pool))
    out.write(tests_markdown(rows))
    if skipped:
        many = len(skipped) != 1
        out.write(f"\n## Skipped\n\n{len(skipped)} path{'s' if many else ''} given or found "
                  f"that {'are' if many else 'is'} not a run:\n\n"
                  + "".join(f"- {s.line()}\n" for s in skipped))
    rob = [r for r in rows if "nominal" in r]
    if rob and levels:
        out.write("\n## Each champion under noise\n\nmean / worst of the replays at each level, and "
                  "the mean as a share of the nominal return and of the champion's recorded fitness "
                  "(- where that is not positive).")
        if judged:
            held = sum(_holds(r) for r in rob)
            out.write(f" **{held} of {len(rob)} champions hold.** Verdict, {_rule(rob)}.")
        out.write("\n\n| run | champion | nominal |" + "".join(f" ±{e:g} mean / worst | ±{e:g} share of "
                                                              f"nominal / of champion |" for e in levels)
                  + (" verdict |" if judged else "") + "\n")
        out.write("|---" * (3 + 2 * len(levels) + judged) + "|\n")

        def pct(x: float) -> str:
            return f"{int(round(100 * x))} %" if math.isfinite(x) else "-"

        for r in sorted(rob, key=lambda r: r["run"]):
            cells = []
            for e in levels:
                ratio = r.get(noise_column(e, "ratio"), math.nan)
                mean, champ = r[noise_column(e, "mean")], champion_figure(r)
                cells += [f"{mean:.3f} / {r[noise_column(e, 'min')]:.3f}",
                          f"{pct(ratio)} / {pct(mean / champ if champ > 0 else math.nan)}"]
            if judged:
                cells.append(f"**{'holds' if _holds(r) else 'knife-edge'}**")
            out.write(f"| {r['run']} | {champion_figure(r):.3f} | {r['nominal']:.3f} | "
                      + " | ".join(cells) + " |\n")
    return out.getvalue()


GROUP_HEAD = {"method": "method", "task": "task", "shape": "shape", "pop": "pop",
              "generations": "generations", "steps": "steps", "evaluation": "evaluation",
              "selection": "final selection",
              "precision": "precision", "arch": "arch", "start": "origin"}


def _groups(rows: list[dict]) -> dict[tuple[str, str], list[dict]]:
    """The rows of each (label, task), in sorted order."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in rows:
        groups[(r["method"], r["task"])].append(r)
    return dict(sorted(groups.items()))


def groups_markdown(rows: list[dict], pool: Sequence[str] = ()) -> str:
    """The groups the table averages over, each with its settings and runs, and which groups of a
    task were kept apart and by what (rows from `summarize`; "" for rows without settings)."""
    from evolve.report.groups import SETTINGS

    groups = {k: rs for k, rs in _groups(rows).items() if "settings" in rs[0]}
    if not groups:
        return ""
    out = io.StringIO()
    out.write("\n## Groups\n\nEach row of the table averages the runs of one group: runs that differ "
              "in their seed alone" + (f" or in {', '.join(pool)} (`--pool`)" if pool else "") + ".\n\n")
    out.write("| " + " | ".join([*GROUP_HEAD.values(), "runs"]) + " |\n"
              + "|---" * (len(SETTINGS) + 1) + "|\n")
    for (label, _), rs in groups.items():
        st = rs[0]["settings"]
        out.write(f"| {label} | " + " | ".join(st[k] for k in SETTINGS[1:]) + " | "
                  + ", ".join(r["run"] for r in rs) + " |\n")
    apart: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for rs in groups.values():
        apart[(rs[0].get("classic", rs[0]["method"]), rs[0]["task"])].append(rs[0]["settings"])
    notes = []
    for (classic, task), settings in sorted(apart.items()):
        differ = [k for k in SETTINGS[2:] if len({st[k] for st in settings}) > 1]
        if len(settings) > 1 and differ:
            notes.append(f"{classic} on {task}: {len(settings)} groups, which differ in "
                         f"{', '.join(differ)} (`--pool {','.join(differ)}` averages them)")
    if notes:
        out.write("\n**Not averaged together:** " + "; ".join(notes) + ".\n")
    return out.getvalue()


NA = "n/a (need >= 2 runs per method)"


def mann_whitney(a: Sequence[float], b: Sequence[float]) -> dict | None:
    """The two-sided Mann-Whitney U test of samples a and b (scipy.stats.mannwhitneyu, its default
    method: exact for small samples without ties, else the normal approximation) with the
    Vargha-Delaney effect size A12 = U / (n_a n_b), the probability that a value of a exceeds one of
    b (ties count half): 0.5 no difference; NaNs dropped; None with fewer than 2 values a side."""
    from scipy.stats import mannwhitneyu

    a = [float(x) for x in a if not math.isnan(x)]
    b = [float(x) for x in b if not math.isnan(x)]
    if len(a) < 2 or len(b) < 2:
        return None
    res = mannwhitneyu(a, b, alternative="two-sided")
    u = float(res.statistic)
    return {"u": u, "p": float(res.pvalue), "a12": u / (len(a) * len(b)), "n": (len(a), len(b))}


def method_tests(rows: list[dict]) -> list[dict]:
    """A Mann-Whitney U test (`mann_whitney`) for each pair of groups of one task that differ in
    their method alone, on each run's champion fitness (champion.json), or where a run of the two
    has none, on the best fitness it found (`end`)."""
    from evolve.report.groups import SETTINGS

    alike: dict[tuple, list[tuple[str, list[dict]]]] = defaultdict(list)
    for (label, _), rs in _groups(rows).items():
        if "settings" in rs[0]:
            alike[tuple(rs[0]["settings"][k] for k in SETTINGS if k != "method")].append((label, rs))
    out = []
    for others, groups in alike.items():
        for (la, ra), (lb, rb) in itertools.combinations(groups, 2):
            both = ra + rb
            on = ("champion" if all(math.isfinite(r.get("champion_fitness", math.nan)) for r in both)
                  else "end")
            values = champion_figure if on == "champion" else (lambda r: r["best_final"])
            test = mann_whitney([values(r) for r in ra], [values(r) for r in rb])
            out.append({"task": others[0], "a": la, "b": lb, "on": on, "n": (len(ra), len(rb)),
                        "test": test})
    return out


def tests_markdown(rows: list[dict]) -> str:
    """report.md's section of `method_tests` ("" when no two methods are comparable)."""
    tests = method_tests(rows)
    if not tests:
        return ""
    out = io.StringIO()
    out.write("\n## Between methods\n\nA two-sided Mann-Whitney U test (scipy.stats.mannwhitneyu) for each "
              "pair of groups of a task that differ in their method alone, on each run's *champion* "
              "fitness (champion.json; *end*: the best fitness found, where a run has no champion). U is "
              "A's statistic; A12 (Vargha-Delaney) = U / (n_A n_B), the probability that a run of A "
              "scores above a run of B, ties counting half: 0.5 is no difference, above 0.71 or below "
              "0.29 a large effect. The p-values are not corrected for the number of tests.\n\n")
    out.write("| task | A | B | on | runs A / B | U | p | A12 |\n" + "|---" * 8 + "|\n")
    for t in tests:
        r = t["test"]
        cells = (["-", NA, "-"] if r is None else [f"{r['u']:g}", f"{r['p']:.3g}", f"{r['a12']:.2f}"])
        out.write(f"| {t['task']} | {t['a']} | {t['b']} | {t['on']} | {t['n'][0]} / {t['n'][1]} | "
                  + " | ".join(cells) + " |\n")
    return out.getvalue()


def _holds(row: dict) -> bool:
    """A summary row's verdict: its champion's recorded headline verdict, else the report's own
    replays at the rule's noise level judged by the rule."""
    if row.get("headline_verdict"):
        return row["headline_verdict"] == "holds"
    return _verdict(row).holds


def _verdict(row: dict) -> verdict_rule.Verdict:
    """A summary row's verdict (evolve/records/verdict.py) from its replays at the rule's noise level."""
    return verdict_rule.Verdict(row["nominal"], row[noise_column(verdict_rule.EPS, "mean")],
                                row.get("replays", 0), verdict_rule.EPS)


def _rule(rows: list[dict]) -> str:
    """The verdict's rule as the report applies it (with its own replay count)."""
    counts = sorted({r.get("replays", 0) for r in rows})
    n = "/".join(str(c) for c in counts)
    return verdict_rule.RULE.replace(f"{verdict_rule.REPLAYS} replays", f"{n} replays")


# summary.csv's columns of a run's group settings (evolve/report/groups.py; `generations` there is
# the planned count, the `generations` column the count run)
SETTING_COLUMNS = ("shape", "pop", "steps", "evaluation", "selection", "precision", "arch", "start")


# summary.csv's columns of a run's champion body (evolve/methods/body_measures.py: its bounding box's
# width and height, the share of its box it fills, each material's share of its voxels and both
# actuators' together, symmetries, irregularity) and of its last generation's population
# (body_diversity, generations.csv's last row): empty where a run has no body or no such column
BODY_COLUMNS = ("width", "height", "fill", "rigid", "soft", "h_actuator", "v_actuator", "actuator",
                "symmetry_lr", "symmetry_tb", "irregularity", "body_diversity")


def write_summary_csv(rows: list[dict], path: Path) -> None:
    """Write `rows` to `path` (replaced) with `summary_columns` of the rows' noise levels in order,
    then the settings of each run's group (SETTING_COLUMNS, where the rows have them), then
    `backend` (where the run ran: `backend_summary`), then BODY_COLUMNS: missing values empty, other
    keys dropped; then each registered section's columns where some row has them."""
    setting = SETTING_COLUMNS if any("settings" in r for r in rows) else ()
    columns = summary_columns(_levels(rows)) + list(setting) + ["backend"] + list(BODY_COLUMNS)
    for section in SECTIONS.values():  # where some run has them (evolve/report/sections.py)
        if section.columns and any(section.columns[0] in r for r in rows):
            columns += list(section.columns)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    for r in rows:
        w.writerow({k: r.get(k, r.get("settings", {}).get(k, "")) for k in columns})
    atomic_write(path, buf.getvalue().encode())


PAGE_PX = 1200  # report.html's width: the curves are shown that wide
CURVES_DPI = 110
CURVES_FONT_PT = 10  # the size the curves' text should have on the page


def plot_curves(runs: list[Path], path: Path, pool: Sequence[str] = ()) -> Path:
    """`_plot_curves` with its text sized for report.html: a row of three panels is drawn 1,980
    pixels wide and shown 1,200 wide, so matplotlib's 10-point text would read as 6-point there."""
    from matplotlib import rc_context

    from evolve.report.plots import diversity_columns

    width_px = 6 * (1 + len(diversity_columns(runs))) * CURVES_DPI
    scale = max(1.0, width_px / PAGE_PX)
    with rc_context({"font.size": CURVES_FONT_PT * scale, "lines.linewidth": 1.5 * scale}):
        return _plot_curves(runs, path, pool)


def _plot_curves(runs: list[Path], path: Path, pool: Sequence[str] = ()) -> Path:
    """One row of panels per task (tasks never share a y axis): mean best-so-far fitness per group
    (evolve/report/groups.py) with a ± sd band over seeds, over the runs' generations, and the
    authors' SGR figures as markers at the generations the runs reached, only where the runs used
    the paper's episode lengths (as the authors did); beside it, where the runs record them, the
    mean species count and body diversity per generation, drawn the same way."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from evolve.report.groups import group_of_each_run
    from evolve.report.plots import DIVERSITY, diversity_columns

    group_of = group_of_each_run(runs, pool)
    extra = diversity_columns(runs)
    by_task: dict[str, dict[str, dict[str, list[np.ndarray]]]] = defaultdict(
        lambda: defaultdict(lambda: defaultdict(list)))
    steps: dict[tuple[str, str], list] = defaultdict(list)
    classic: dict[str, str] = {}
    for d in runs:
        g = group_of[d]
        classic[g.label] = g.classic
        raw = load_yaml(read_text(d / "config.yaml", CONFIG_CAP)) or {}
        steps[(g.label, g.task)].append(episode_length(raw, g.task))
        cols = read_generations(d)
        b = best_so_far(cols)
        if len(b):
            by_task[g.task][g.label]["best"].append(b)
            for column in extra:
                if column in cols:
                    by_task[g.task][g.label][column].append(cols[column])
    tasks = sorted(by_task)
    n_cols = 1 + len(extra)
    fig = Figure(figsize=(6 * n_cols, 3.8 * len(tasks)))
    FigureCanvasAgg(fig)
    from evolve.report.plots import matplotlib_colors

    cycle = matplotlib_colors()
    color = {label: cycle[i] for i, label in enumerate(sorted({m for t in by_task.values() for m in t}))}
    for i, task in enumerate(tasks):
        ax = fig.add_subplot(len(tasks), n_cols, i * n_cols + 1)
        sides = [fig.add_subplot(len(tasks), n_cols, i * n_cols + 2 + j) for j in range(len(extra))]
        for method, series in sorted(by_task[task].items()):
            curves = series["best"]
            seeds = f"{len(curves)} seed{'s' if len(curves) != 1 else ''}"
            band(ax, curves, color[method], f"{method} ({seeds})")
            for side, column in zip(sides, extra, strict=True):
                if series[column]:
                    band(side, series[column], color[method], method)
        last = max(len(c) for m in by_task[task].values() for c in m["best"])
        for method in sorted(by_task[task]):  # the authors' figures at generations 1, 30, 100
            known = [(g, v) for g, v in zip(CHECKPOINTS, AUTHORS.get((classic[method], task), ())[:3],
                                            strict=False)
                     if isinstance(v, float) and g <= last]  # the x-axis stays the runs'
            if authors_not_comparable(task, steps[(method, task)]):
                continue  # other episode lengths: no marker (report.md says why)
            if known and classic[method] == "sgr":  # their other methods' logs are doubtful (docs/RESULTS.md)
                ax.plot(*zip(*known, strict=True), "kx", label="sgr, authors' logs")
        for a, title, ylabel in [(ax, task, "best fitness"),
                                 *((side, f"{task}: {DIVERSITY[c].splitlines()[0]}", DIVERSITY[c])
                                   for side, c in zip(sides, extra, strict=True))]:
            a.set_title(title)
            a.set_xlabel("generation")
            a.xaxis.set_major_locator(MaxNLocator(integer=True))
            a.set_xlim(0.5, last + 0.5)
            a.set_ylabel(ylabel)
            a.grid(alpha=0.3)
            if a.get_lines():
                a.legend(fontsize="small")
    fig.tight_layout()
    return save_png(fig, path, dpi=CURVES_DPI)


def write_report(folder: str | Path | Sequence[str | Path], out: str | Path | None = None,
                 robustness: bool = True, levels: Sequence[float] = NOISE_LEVELS, replays: int = 10,
                 gallery: bool = True, pool: Sequence[str] = (),
                 say: Callable[[str], None] | None = None) -> Path:
    """report.md (at `out`, default <first folder>/report.md), summary.csv, curves.png and
    report.html beside it, of the runs at any depth below one folder or several (e.g. a sweep and
    its robust twin), grouped by the settings that make them comparable (but those in `pool`);
    each champion replayed `replays` times at each noise level in `levels`; `gallery`: the best
    seed's champion per group as a GIF and a body picture in gallery/, inlined in report.html;
    a map-elites run's archive and elites chosen across it in archives/ (evolve/report/archive.py).
    `say` gets one line per path skipped and per group."""
    from evolve.report.gallery import gallery_entries, markdown_html, report_html, write_gallery

    folders = [folder] if isinstance(folder, str | Path) else list(folder)
    runs, skipped = find_report_runs(folders)
    out = Path(out) if out else Path(folders[0]) / "report.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    rows = summarize(runs, robustness, levels, replays, pool)
    if say is not None:
        for s in skipped:
            say(f"skipped {s.line()}")
        groups = _groups(rows)
        say(f"{len(runs)} run{'s' if len(runs) != 1 else ''} in {len(groups)} group"
            f"{'s' if len(groups) != 1 else ''} (runs that differ in their seed alone"
            + (f" or in {', '.join(pool)}" if pool else "") + "):")
        for (label, task), rs in groups.items():
            say(f"  {label} / {task}: {len(rs)} run{'s' if len(rs) != 1 else ''} "
                f"({', '.join(r['run'] for r in rs)})")
    main = report_markdown(rows, skipped, pool)
    parts = [s.part(rows, runs, out.parent, pool) for s in SECTIONS.values() if s.part is not None]
    text = main + "".join(p.markdown for p in parts)
    atomic_write(out, text.encode())
    write_summary_csv(rows, out.parent / "summary.csv")
    curves = plot_curves(runs, out.parent / "curves.png", pool)
    shown = (write_gallery(gallery_entries(rows, {r["run"]: r["path"] for r in rows}), out.parent / "gallery")
             if gallery else [])
    extra = [h for p in parts for h in (p.html if p.html is not None else [markdown_html(p.markdown)])
             if h]  # (a section's text once: as its own HTML where it has some, e.g. inlined pictures)
    page = report_html(main, curves, shown, extra)
    atomic_write(out.parent / "report.html", page.encode())
    return out
