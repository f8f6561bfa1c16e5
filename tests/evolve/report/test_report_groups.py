"""Reports you can publish (#45): `sgr report` averages only runs that differ in their seed alone
(`--pool` to average across a setting), finds runs at any depth and names what it skipped, tests
methods against each other (Mann-Whitney U, A12); `sgr plot` passes over what is not a run and
draws one row of panels per task. The runs are written by hand here, so every expected number
follows from this file (scipy is the oracle for p-values)."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest
import yaml
from matplotlib.figure import Figure
from scipy.stats import mannwhitneyu

from evolve.cli import main
from evolve.report.report import mann_whitney, write_report

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def make_run(path: Path, method: str = "sgr", task: str = "Walker-v0", seed: int = 0,
             best: tuple[float, ...] = (1.0, 2.0), champion: float | None = None, **cfg) -> Path:
    """A run folder as sgr writes it: config.yaml, generations.csv (species and body diversity
    too), and champion.json with `champion` as its fitness."""
    path.mkdir(parents=True)
    (path / "config.yaml").write_text(yaml.safe_dump({"method": method, "task": task, "seed": seed,
                                                      "generations": len(best), "pop_size": 8, **cfg}))
    lines = ["generation,best,mean,median,n_species,total_s,body_diversity"]
    lines += [f"{g},{b!r},{b / 2!r},{b / 2!r},{g},1.0,{0.5 / g!r}" for g, b in enumerate(best, start=1)]
    (path / "generations.csv").write_text("\n".join(lines) + "\n")
    if champion is not None:
        (path / "champion.json").write_text(json.dumps({"fitness": champion}))
    return path


def table_rows(text: str) -> dict[str, dict[str, str]]:
    """The cells of report.md's first table by its first two cells ("method / task"), each row's
    cells by their column's heading."""
    table = text[text.index("| method | task |"):].split("\n\n")[0].splitlines()
    head = [c.strip() for c in table[0].strip().strip("|").split("|")]
    rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in table[2:]]
    return {f"{r[0]} / {r[1]}": dict(zip(head, r, strict=True)) for r in rows}


def report(folder, **kw) -> tuple[str, list[str]]:
    lines: list[str] = []
    out = write_report(folder, robustness=False, gallery=False, say=lines.append, **kw)
    return out.read_text(), lines


def test_runs_of_different_populations_precisions_or_arches_are_separate_rows(tmp_path):
    """Two seeds each at pop 8 and pop 16: two rows, each named by what sets it apart, never one
    mean of four; a precision or arch of its own is its own row too; --pool pop averages the pops."""
    runs = tmp_path / "runs"
    for seed, b in ((0, 1.0), (1, 3.0)):
        make_run(runs / f"small-{seed}", seed=seed, best=(b,))
    for seed, b in ((0, 10.0), (1, 20.0)):
        make_run(runs / f"big-{seed}", seed=seed, best=(b,), pop_size=16)
    text, lines = report(runs)
    rows = table_rows(text)
    assert set(rows) == {"sgr (pop 8) / Walker-v0", "sgr (pop 16) / Walker-v0"}
    assert [rows["sgr (pop 8) / Walker-v0"][k] for k in ("runs (seeds)", "generations")] == ["2 (seeds 0, 1)",
                                                                                            "1"]
    assert rows["sgr (pop 8) / Walker-v0"]["end"] == "2.00 ± 1.41"  # end: 1 and 3
    assert rows["sgr (pop 16) / Walker-v0"]["end"] == "15.00 ± 7.07"  # 10 and 20
    assert "differ in pop (`--pool pop` averages them)" in text
    assert "| sgr (pop 16) | Walker-v0 | 5x5 | 16 | 1 |" in text  # the groups table: settings and runs
    assert any(line.startswith("  sgr (pop 16) / Walker-v0: 2 runs (big-0, big-1)") for line in lines)
    summary = {r["run"]: (r["method"], r["pop"]) for r in csv.DictReader((runs / "summary.csv").open())}
    assert summary == {"small-0": ("sgr (pop 8)", "8"), "small-1": ("sgr (pop 8)", "8"),
                       "big-0": ("sgr (pop 16)", "16"), "big-1": ("sgr (pop 16)", "16")}

    pooled, _ = report(runs, pool=("pop",))
    assert list(table_rows(pooled)) == ["sgr / Walker-v0"]
    assert table_rows(pooled)["sgr / Walker-v0"]["end"] == "8.50 ± 8.58"  # 1, 3, 10, 20: sd sqrt(221 / 3)
    assert "| 16 / 8 (pooled) |" in pooled

    shutil.rmtree(runs)
    make_run(runs / "a", precision="f32", arch="cpu")
    make_run(runs / "b", seed=1, precision="f64", arch="cpu")
    make_run(runs / "c", seed=2, precision="f64", arch="cuda")
    assert set(table_rows(report(runs)[0])) == {"sgr (f32, arch cpu) / Walker-v0",
                                                "sgr (f64, arch cpu) / Walker-v0",
                                                "sgr (f64, arch cuda) / Walker-v0"}


def test_maps_over_other_descriptors_or_bred_otherwise_are_other_methods(tmp_path):
    """Map-elites over the body (the default descriptors), over behaviour, and over the body with
    curiosity parents (issue 58's three arms, seeds 0 and 1 each): three rows, each the mean of its
    own two seeds, named by what its map does differently, never one mean of six runs."""
    runs = tmp_path / "runs"
    arms = {"body": ({"descriptors": ["actuator", "rigid"]}, (1.0, 3.0)),
            "behaviour": ({"descriptors": ["gait_frequency", "contact"], "selection": "curiosity",
                           "exploit": 0.5}, (10.0, 20.0)),
            "curious": ({"selection": "curiosity", "exploit": 0.0}, (100.0, 300.0))}
    for arm, (qd, bests) in arms.items():
        for seed, b in enumerate(bests):
            make_run(runs / f"{arm}-{seed}", method="map-elites", seed=seed, best=(b,), qd=qd)
    rows = table_rows(report(runs)[0])
    assert set(rows) == {"map-elites / Walker-v0",
                         "map-elites (gait_frequency x contact, curiosity, exploit 0.5) / Walker-v0",
                         "map-elites (curiosity) / Walker-v0"}
    assert rows["map-elites / Walker-v0"]["end"] == "2.00 ± 1.41"
    assert rows["map-elites (gait_frequency x contact, curiosity, exploit 0.5) / Walker-v0"]["end"] == \
        "15.00 ± 7.07"
    assert rows["map-elites (curiosity) / Walker-v0"]["runs (seeds)"] == "2 (seeds 0, 1)"


def test_runs_at_depth_two_and_more_are_reported_and_what_is_not_a_run_is_named(tmp_path):
    """Runs two and three folders down are found; a decoded champion, a half-made run, a folder
    of pictures and a file given are listed as skipped, each with why, on the console and in
    report.md."""
    make_run(tmp_path / "study" / "sweep" / "runs" / "sgr-Walker-v0-s0")
    make_run(tmp_path / "study" / "other" / "sgr-Walker-v0-s1", seed=1)
    (tmp_path / "study" / "decoded").mkdir()
    (tmp_path / "study" / "decoded" / "champion.json").write_text("{}")
    (tmp_path / "study" / "half").mkdir()
    (tmp_path / "study" / "half" / "config.yaml").write_text("method: sgr\n")
    (tmp_path / "study" / "pictures").mkdir()
    (tmp_path / "study" / "pictures" / "a.png").write_bytes(PNG_MAGIC)
    (tmp_path / "notes.txt").write_text("x")
    lines: list[str] = []
    out = write_report([tmp_path / "study", tmp_path / "notes.txt"], tmp_path / "r" / "report.md",
                       robustness=False, gallery=False, say=lines.append)
    text = out.read_text()
    assert table_rows(text)["sgr / Walker-v0"]["runs (seeds)"] == "2 (seeds 1, 0)"  # in the order found:
    # other/ before sweep/
    assert "| other/sgr-Walker-v0-s1, sweep/runs/sgr-Walker-v0-s0 |" in text  # named below study/
    skipped = text[text.index("## Skipped"):]
    expect = {"decoded": "a champion.json alone", "half": "config.yaml but no generations.csv",
              "pictures": "no run folder in it", "notes.txt": "a file, not a run folder"}
    for name, why in expect.items():
        assert any(name in line and why in line for line in skipped.splitlines()), name
        assert any(line.startswith("skipped ") and name in line and why in line for line in lines), name


def test_mann_whitney_p_and_a12_match_scipy_on_known_fitness(tmp_path):
    """Champion fitness sgr 1, 2, 3, 5 against direct 0.5, 1.5, 2.5: sgr beats direct in 9 of 12
    pairs, so U = 9 and A12 = 0.75; the p-value is scipy's two-sided one. A method with one run
    gets n/a."""
    runs = tmp_path / "runs"
    for seed, f in enumerate((1.0, 2.0, 3.0, 5.0)):
        make_run(runs / f"sgr-{seed}", seed=seed, champion=f)
    for seed, f in enumerate((0.5, 1.5, 2.5)):
        make_run(runs / f"direct-{seed}", method="direct", seed=seed, champion=f)
    make_run(runs / "nested-0", method="nested", champion=9.0)
    text, _ = report(runs)
    p = mannwhitneyu([0.5, 1.5, 2.5], [1.0, 2.0, 3.0, 5.0], alternative="two-sided").pvalue
    tests = {(c[1], c[2]): c for c in ([x.strip() for x in line.strip().strip("|").split("|")]
                                       for line in text[text.index("## Between methods"):].splitlines()
                                       if line.startswith("| Walker-v0"))}
    assert tests[("direct", "sgr")] == ["Walker-v0", "direct", "sgr", "champion", "3 / 4", "3",
                                        f"{p:.3g}", "0.25"]
    assert tests[("direct", "nested")][5:] == ["-", "n/a (need >= 2 runs per method)", "-"]
    r = mann_whitney([1.0, 2.0, 3.0, 5.0], [0.5, 1.5, 2.5])
    assert r["u"] == 9 and r["a12"] == 0.75
    assert r["p"] == pytest.approx(mannwhitneyu([1, 2, 3, 5], [0.5, 1.5, 2.5]).pvalue, rel=1e-12)


def test_without_a_champion_the_test_is_on_the_best_fitness_found(tmp_path):
    runs = tmp_path / "runs"
    for seed, b in enumerate((1.0, 2.0)):
        make_run(runs / f"sgr-{seed}", seed=seed, best=(b,), champion=b)
    for seed, b in enumerate((3.0, 4.0)):
        make_run(runs / f"direct-{seed}", method="direct", seed=seed, best=(b,))  # no champion.json
    text, _ = report(runs)
    line = next(x for x in text.splitlines() if x.startswith("| Walker-v0 | direct | sgr |"))
    assert "| end | 2 / 2 | 4 |" in line and line.endswith("| 1.00 |")  # direct above sgr in all 4 pairs


def test_pool_names_a_setting_or_is_refused_in_one_line(tmp_path, capsys):
    make_run(tmp_path / "runs" / "a")
    assert main(["report", str(tmp_path / "runs"), "--pool", "pop,colour", "--no-robustness"]) == 2
    err = capsys.readouterr().err
    assert "--pool 'colour': not a setting" in err and err.count("\n") == 1
    assert main(["plot", str(tmp_path / "runs" / "a"), "--pool", "task"]) == 2
    assert "never averaged together" in capsys.readouterr().err


@pytest.mark.slow
def test_sgr_plot_runs_star_works_after_plot_report_and_decode_wrote_there(tmp_path, sgr_run, capsys,
                                                                           monkeypatch):
    """`sgr plot runs/*` once runs/ holds fitness.png, report.md, summary.csv, curves.png,
    report.html, gallery/ and a decoded champion: every one is skipped and named, the runs plotted."""
    runs = tmp_path / "runs"
    shutil.copytree(sgr_run, runs / "sgr-a")
    make_run(runs / "direct-a", method="direct", seed=3, episode_steps=20)
    monkeypatch.chdir(tmp_path)

    def sgr_plot_runs_star() -> str:
        capsys.readouterr()
        assert main(["plot", *sorted(str(p.relative_to(tmp_path)) for p in runs.iterdir())]) == 0
        return capsys.readouterr().out

    sgr_plot_runs_star()
    assert main(["report", "runs", "--no-robustness"]) == 0
    assert main(["decode", "runs/sgr-a", "--shape", "6x6"]) == 0
    out = sgr_plot_runs_star()
    assert out.strip().endswith(f"wrote {runs / 'fitness.png'}")
    assert (runs / "fitness.png").read_bytes()[:8] == PNG_MAGIC
    for name in ("fitness.png", "report.md", "summary.csv", "curves.png", "report.html"):
        assert f"skipped runs/{name}: a file, not a run folder" in out
    assert "skipped runs/gallery: no generations.csv in it" in out
    assert "skipped runs/sgr-a-6x6: a champion.json alone" in out
    assert main(["report", "runs", "--no-robustness", "--no-gallery"]) == 0  # and report, again
    assert "runs/sgr-a-6x6: a champion.json alone" in (runs / "report.md").read_text()


def _fitness_axes(fig: Figure) -> dict[str, object]:
    return {ax.get_title(): ax for ax in fig.axes if ax.get_ylabel() == "best fitness"}


def test_one_panel_per_task_in_plots_and_report_curves_with_species_and_body_diversity(tmp_path, saved):
    """Walker-v0 (fitness ~1) and Climber-v2 (fitness ~100) in one plot: each task its own fitness
    panel, whose lines are its own runs', and beside each a species and a body diversity panel."""
    from evolve.report.plots import plot_runs
    from evolve.report.report import plot_curves

    runs = [make_run(tmp_path / "w0", best=(1.0, 2.0)), make_run(tmp_path / "w1", seed=1, best=(1.5, 2.5)),
            make_run(tmp_path / "c0", task="Climber-v2", best=(100.0, 200.0))]
    plot_runs(runs, tmp_path / "fitness.png")
    fig = saved[-1]
    panels = _fitness_axes(fig)
    walker = panels.pop("Best fitness per generation: Walker-v0")
    climber = panels.pop("Best fitness per generation: Climber-v2")
    assert not panels
    assert [line.get_label().split(" (")[0] for line in walker.get_lines()] == ["sgr / Walker-v0"]
    assert list(walker.get_lines()[0].get_ydata()) == [1.25, 2.25]
    assert list(climber.get_lines()[0].get_ydata()) == [100.0, 200.0]
    assert walker.get_ylim()[1] < 100 and walker.get_shared_y_axes().get_siblings(walker) == [walker]
    titles = [ax.get_title() for ax in fig.axes]
    assert {"Walker-v0: species", "Walker-v0: body diversity", "Climber-v2: species",
            "Climber-v2: body diversity"} <= set(titles) and len(titles) == 6
    diversity = next(ax for ax in fig.axes if ax.get_title() == "Walker-v0: body diversity")
    assert list(diversity.get_lines()[0].get_ydata()) == [0.5, 0.25]  # the runs' 0.5 / g

    plot_curves(runs, tmp_path / "curves.png")
    fig = saved[-1]
    assert sorted(ax.get_title() for ax in fig.axes if ax.get_ylabel() == "best fitness") == [
        "Climber-v2", "Walker-v0"]
    assert len(fig.axes) == 6


def test_old_runs_without_body_diversity_plot_and_report(tmp_path, saved):
    """A run made before body_diversity was recorded: no diversity panel of it, nothing fails."""
    from evolve.report.plots import plot_runs

    run = make_run(tmp_path / "runs" / "old")
    rows = (run / "generations.csv").read_text().splitlines()
    (run / "generations.csv").write_text("\n".join(r.rsplit(",", 1)[0] for r in rows) + "\n")
    plot_runs([run], tmp_path / "f.png")
    assert [ax.get_title() for ax in saved[-1].axes][1:] == ["Walker-v0: species"]
    text, _ = report(tmp_path / "runs")
    assert "sgr / Walker-v0" in table_rows(text)


def test_sgr_plot_of_one_run_draws_its_species_and_body_diversity(tmp_path, saved, capsys):
    """`sgr plot RUN`: the run's fitness and, beside it, its species and body diversity (the run's
    0.5 / g); the run's own end file (plot_run's default) keeps to fitness."""
    from evolve.report.plots import plot_run

    run = make_run(tmp_path / "run", best=(1.0, 2.0, 3.0))
    assert main(["plot", str(run)]) == 0
    titles = {ax.get_title(): ax for ax in saved[-1].axes}
    assert set(titles) == {"sgr / Walker-v0: run", "species", "body diversity"}
    assert list(titles["species"].get_lines()[0].get_ydata()) == [1, 2, 3]
    assert list(titles["body diversity"].get_lines()[0].get_ydata()) == [0.5, 0.25, 0.5 / 3]
    plot_run(run, tmp_path / "end.png")
    assert len(saved[-1].axes) == 1


def test_a_run_resumed_on_another_arch_is_grouped_by_the_arches_its_segments_record(tmp_path):
    """segments.json (one entry per start and resume) decides the arch setting: a run started on
    CUDA and resumed on the CPU is not averaged with runs that ran on the CPU alone."""
    runs = tmp_path / "runs"
    for name, seed, arches in (("a", 0, ["cpu"]), ("b", 1, ["cpu"]), ("c", 2, ["cuda", "cpu"])):
        run = make_run(runs / name, seed=seed)
        (run / "segments.json").write_text(json.dumps(
            [{"after_generation": g, "arch": a, "precision": "f64"} for g, a in enumerate(arches)]))
    rows = table_rows(report(runs)[0])
    assert set(rows) == {"sgr (arch cpu) / Walker-v0", "sgr (arch cuda, then cpu) / Walker-v0"}, rows


def test_one_run_says_one_run_and_its_seed_and_shows_no_spread(tmp_path):
    """A lone run with seed 0 reads "1 (seed 0)", not "0" (read as zero seeds), and its figures
    carry no "± 0.00" (a spread no one measured)."""
    make_run(tmp_path / "runs" / "only", seed=0, best=(1.0, 2.5))
    text, _ = report(tmp_path / "runs")
    row = table_rows(text)["sgr / Walker-v0"]
    assert row["runs (seeds)"] == "1 (seed 0)"
    assert row["end"] == "2.50"
    assert "± 0.00" not in text


def test_a_task_outside_the_paper_gets_no_authors_column_and_no_generation_it_never_reached(tmp_path):
    """Carrier-v0 runs of 5 generations: no "authors" column (the paper has no figures for it) and no
    "gen 30" / "gen 100" columns (always empty); a Walker-v0 run of 40 beside them brings the
    authors' column and gen 30, not gen 100."""
    for seed in (0, 1):
        make_run(tmp_path / "a" / f"carrier-{seed}", task="Carrier-v0", seed=seed, best=(1.0,) * 5)
    head = next(iter(table_rows(report(tmp_path / "a")[0]).values()))
    assert list(head) == ["method", "task", "runs (seeds)", "generations", "gen 1", "end", "champion",
                          "nominal"]
    make_run(tmp_path / "a" / "walker", seed=0, best=(1.0,) * 40)
    rows = table_rows(report(tmp_path / "a")[0])
    assert list(rows["sgr / Walker-v0"])[4:8] == ["gen 1", "gen 30", "end", "authors (1 / 30 / 100 / end)"]
    assert rows["sgr / Carrier-v0"]["authors (1 / 30 / 100 / end)"] == "-"
