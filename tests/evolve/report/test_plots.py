"""Fitness plots: runs grouped by (method, task), one curve and min..max band per group, PNGs."""

import numpy as np
import pytest
import yaml

from evolve.report.plots import draw_curves, plot_run, plot_runs, run_labels, summarize_runs

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _run(path, best, method=None, task="Walker-v0", first=1):
    """A run directory with these best fitnesses; generations counted from `first` (0: a run
    written before generations were counted from 1)."""
    path.mkdir(parents=True)
    if method is not None:
        (path / "config.yaml").write_text(yaml.safe_dump({"method": method, "task": task, "seed": 0}))
    lines = ["generation,best,mean,median,n_species"]
    lines += [f"{g},{b!r},{b / 2!r},{b / 3!r},3" for g, b in enumerate(best, start=first)]
    (path / "generations.csv").write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def runs(tmp_path):
    return [_run(tmp_path / "sgr-0", [1.0, 2.0, 3.0], "sgr"),
            _run(tmp_path / "sgr-1", [3.0, 4.0], "sgr"),  # shorter run (still going)
            _run(tmp_path / "direct-0", [0.5, 0.5, float("-inf")], "direct")]


def test_groups_are_method_task_pairs_with_mean_and_min_max(runs):
    """Two methods on one task give two groups; sgr's curve is the seed mean with a min..max band,
    later generations use the runs that reached them, and -inf (no valid robot) is left out."""
    curves = summarize_runs(runs)
    assert set(curves) == {("sgr", "Walker-v0"), ("direct", "Walker-v0")}
    sgr = curves[("sgr", "Walker-v0")]
    assert sgr.n_runs == 2
    assert sgr.generation.tolist() == [1, 2, 3]
    assert np.allclose(sgr.mean, [2.0, 3.0, 3.0])
    assert np.allclose(sgr.low, [1.0, 2.0, 3.0]) and np.allclose(sgr.high, [3.0, 4.0, 3.0])
    assert curves[("direct", "Walker-v0")].generation.tolist() == [1, 2]


def test_plot_runs_writes_png_with_one_curve_per_group(runs, tmp_path):
    """The comparison PNG exists and its axes hold exactly one labelled line per (method, task)."""
    out = plot_runs(runs, tmp_path / "plots" / "compare.png")
    assert out.read_bytes()[:8] == PNG_MAGIC
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    lines = draw_curves(ax, summarize_runs(runs))
    assert len(lines) == len(ax.get_lines()) == 2
    assert sorted(line.get_label().split(" (")[0] for line in lines) == ["direct / Walker-v0",
                                                                          "sgr / Walker-v0"]
    assert all("min-max" in line.get_label() for line in lines)


def test_plot_run_writes_png(runs, tmp_path):
    """A single run's best/mean/median plot is a PNG file."""
    out = plot_run(runs[0], tmp_path / "one.png")
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_labels_fall_back_without_config(tmp_path):
    """No config.yaml: the method is the parent directory's name, the task "unknown"."""
    run = _run(tmp_path / "my-exp" / "seed-3", [1.0])
    assert run_labels(run) == ("my-exp", "unknown")
    assert set(summarize_runs([run])) == {("my-exp", "unknown")}


def test_labels_keep_sizes_and_grown_runs_apart(tmp_path):
    """A run at another body size, and one grown from another run's population, are their own
    groups in reports and plots; the paper's 5x5 (stated or not) keeps the plain method name."""
    labels = {}
    for name, extra in {"plain": "", "five": "robot_shape: [5, 5]\n", "big": "robot_shape: [10, 10]\n",
                        "grown": "robot_shape: [10, 10]\nstart_from: {run: /x, generation: 50}\n"}.items():
        run = _run(tmp_path / name, [1.0])
        (run / "config.yaml").write_text(f"method: sgr\ntask: Walker-v0\n{extra}")
        labels[name] = run_labels(run)[0]
    assert labels == {"plain": "sgr", "five": "sgr", "big": "sgr 10x10", "grown": "sgr 10x10 from g50"}


def test_plot_runs_without_data_raises(tmp_path):
    """Runs with no generations rows cannot be plotted; say so instead of writing an empty PNG."""
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "generations.csv").write_text("generation,best,mean,median\n")
    with pytest.raises(ValueError, match="no run"):
        plot_runs([empty], tmp_path / "x.png")


def test_numpy_scalar_reprs_are_read_as_numbers(tmp_path):
    """A CSV written with repr() of numpy 2 scalars ("np.float64(1.5)") still gives the numbers."""
    run = tmp_path / "r"
    run.mkdir()
    (run / "generations.csv").write_text("generation,best\n0,np.float64(1.5)\n1,np.float64(2.5)\n")
    curve = next(iter(summarize_runs([run]).values()))
    assert curve.mean.tolist() == [1.5, 2.5]


def test_a_run_counted_from_0_reads_as_counted_from_1(tmp_path):
    """generations.csv of runs made before generations were counted from 1 starts at 0; read, it is
    renumbered, so old and new runs line up in one plot."""
    from evolve.report.plots import read_generations
    old = _run(tmp_path / "old", [1.0, 2.0], "sgr", first=0)
    new = _run(tmp_path / "new", [1.5, 2.5], "sgr")
    assert read_generations(old)["generation"].tolist() == [1, 2]
    assert summarize_runs([old, new])[("sgr", "Walker-v0")].generation.tolist() == [1, 2]


def test_ticks_are_whole_generations_and_per_run_draws_one_line_per_run(tmp_path):
    """A 3-generation run has no tick at 2.5; --per-run draws each run as its own line."""
    from matplotlib.figure import Figure

    import evolve.report.plots as P
    runs = [_run(tmp_path / "a", [1.0, 2.0, 3.0], "sgr"), _run(tmp_path / "b", [0.5, 1.0, 1.5], "sgr"),
            _run(tmp_path / "c", [0.2, 0.4, 0.6], "direct")]
    seen = {}
    real_finish = P._finish

    def spy(fig: Figure, ax, title, ylabel, out):
        path = real_finish(fig, ax, title, ylabel, out)
        seen["ticks"] = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
        seen["lines"] = [line.get_label() for line in ax.get_lines()]
        return path

    P._finish = spy
    try:
        plot_runs(runs, tmp_path / "per-run.png", per_run=True)
        assert len(seen["lines"]) == 3 and seen["lines"][0].endswith(": a")
        assert all(float(t).is_integer() for t in seen["ticks"]) and len(seen["ticks"]) >= 2
        plot_run(runs[0], tmp_path / "one.png")
        assert all(float(t).is_integer() for t in seen["ticks"])
    finally:
        P._finish = real_finish


def test_sgr_plot_of_several_runs_writes_beside_them_and_says_where(tmp_path, monkeypatch, capsys):
    """`sgr plot runs/* --per-run` from another folder: runs/fitness.png, named on stdout; nothing in
    the working folder (its --help says so)."""
    from evolve.cli import main

    runs = [_run(tmp_path / "runs" / "a", [1.0, 2.0], "sgr"),
            _run(tmp_path / "runs" / "b", [0.5, 1.0], "sgr")]
    cwd = tmp_path / "elsewhere"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    assert main(["plot", *map(str, runs), "--per-run"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'runs' / 'fitness.png'}"
    assert (tmp_path / "runs" / "fitness.png").read_bytes().startswith(PNG_MAGIC)
    assert list(cwd.iterdir()) == []


@pytest.mark.parametrize("row, says", [
    ("junk,row", "line 4 has no generation number (got 'junk')"),
    ("7,1.0,0.5,0.3,3", "line 4 is generation 7, not 3"),
    ("2,1.0,0.5,0.3,3", "line 4 is generation 2, not 3"),
    ("\u00b2,1.0,0.5,0.3,3", "line 4 has no generation number (got '\u00b2')"),  # a digit to str.isdigit
    ("\n\n3,1.0,0.5,0.3,3\nx", "line 7 has no generation number (got 'x')"),  # blank lines counted
])
def test_rows_that_are_not_the_next_generation_are_a_damaged_file_not_more_generations(tmp_path, row, says):
    """A junk row in generations.csv was counted as one more generation (with NaN fitness) by `sgr
    report` and `sgr plot`; a row that is not the next generation names the file and the row. A run
    grown from another's checkpoint starts where that one stopped and reads as it is."""
    from evolve.records.rundir import RunDir
    from evolve.report.plots import read_generations
    from tsim.errors import SgrError

    run = _run(tmp_path / "r", [1.0, 2.0])
    with (run / "generations.csv").open("a") as f:
        f.write(row + "\n")
    with pytest.raises(SgrError) as exc:
        read_generations(run)
    assert str(exc.value) == f"{run / 'generations.csv'}: {says}: a damaged file"
    with pytest.raises(SgrError, match="a damaged file"):  # what a resume checks first
        RunDir(run).check_rows()
    grown = _run(tmp_path / "grown", [1.0, 2.0, 3.0], first=51)
    assert read_generations(grown)["generation"].tolist() == [51, 52, 53]


def test_resume_over_a_junk_row_names_the_file_and_the_row(tmp_path):
    from evolve.records.rundir import RunDir
    from tsim.errors import SgrError

    run = _run(tmp_path / "r", [1.0, 2.0, 3.0])
    RunDir(run).truncate_rows(2)
    assert (run / "generations.csv").read_text().splitlines()[-1].startswith("2,")
    with (run / "generations.csv").open("a") as f:
        f.write("x,1.0\n")
    with pytest.raises(SgrError, match=r"generations.csv: line 4 has no generation number \(got 'x'\)"):
        RunDir(run).truncate_rows(1)
    _run(tmp_path / "dup", [1.0, 2.0, 3.0])
    with (tmp_path / "dup" / "generations.csv").open("a") as f:
        f.write("2,1.0,0.5,0.3,3\n")  # a generation twice: resumed and appended to, it would stay wrong
    with pytest.raises(SgrError, match=r"generations.csv: line 5 is generation 2, not 4: a damaged file"):
        RunDir(tmp_path / "dup").truncate_rows(3)


def test_a_figure_is_written_with_a_palette_and_looks_as_drawn(tmp_path):
    """save_png keeps 256 colours (a committed report's PNGs at about a third of the bytes): the picture
    differs from matplotlib's true-colour one by less than half a level in 255 on average."""
    import io

    from matplotlib.figure import Figure
    from PIL import Image

    from evolve.report.plots import save_png

    fig = Figure(figsize=(4, 3))
    ax = fig.add_subplot()
    x = np.linspace(0, 6, 200)
    for k in range(4):
        ax.plot(x, np.sin(x + k), label=f"curve {k}")
        ax.fill_between(x, np.sin(x + k) - 0.2, np.sin(x + k) + 0.2, alpha=0.2)
    ax.legend()
    true = io.BytesIO()
    fig.savefig(true, format="png", dpi=100)
    save_png(fig, tmp_path / "f.png", dpi=100)
    written = Image.open(tmp_path / "f.png")
    assert written.mode == "P" and (tmp_path / "f.png").stat().st_size < 0.45 * len(true.getvalue())
    a = np.asarray(Image.open(true).convert("RGB"), dtype=float)
    b = np.asarray(written.convert("RGB"), dtype=float)
    assert a.shape == b.shape and np.abs(a - b).mean() < 0.5  # 0.19 measured


def test_per_run_gives_each_run_its_own_colour_and_each_group_one_legend_entry(tmp_path, saved):
    """`sgr plot --per-run`: three seeds of sgr and two of direct are five colours (the seeds of a
    group in shades of its colour), and the legend has one entry per group; the diversity panels
    beside carry no legend of their own (it covered their lines)."""
    from matplotlib.colors import to_hex

    runs = [_run(tmp_path / f"s{i}", [1.0 + i, 2.0 + i], "sgr") for i in range(3)]
    runs += [_run(tmp_path / f"d{i}", [0.5, 1.0 + i], "direct") for i in range(2)]
    plot_runs(runs, tmp_path / "per-run.png", per_run=True)
    main, *side = saved[-1].axes
    colours = [to_hex(line.get_color()) for line in main.get_lines()]
    assert len(colours) == 5 and len(set(colours)) == 5, colours
    assert sorted(t.get_text() for t in main.get_legend().get_texts()) == [
        "direct (2 runs, a shade each)", "sgr (3 runs, a shade each)"]
    assert side and all(ax.get_legend() is None for ax in side)
