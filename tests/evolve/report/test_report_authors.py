"""`sgr report` beside the authors: the x-axis is the runs' generations, and the authors' figures
stand beside ours only where the runs used the paper's episode length (else they are marked not
comparable) and only at generations the runs reached."""

import yaml

from evolve.report.report import plot_curves, report_markdown, summarize


def _run(path, best, steps):
    path.mkdir(parents=True)
    (path / "config.yaml").write_text(yaml.safe_dump({"method": "sgr", "task": "Walker-v0", "seed": 0,
                                                      "episode_steps": steps}))
    rows = ["generation,best,mean,median,n_species,total_s"]
    rows += [f"{g},{b},{b},{b},1,1.0" for g, b in enumerate(best, start=1)]
    (path / "generations.csv").write_text("\n".join(rows) + "\n")
    return path


def test_short_episodes_mark_the_authors_figures_not_comparable(tmp_path, saved):
    runs = [_run(tmp_path / "a", [1.0, 2.0, 3.0], 20)]  # 20-step episodes; the paper's Walker-v0: 500
    text = report_markdown(summarize(runs, robustness=False))
    assert "5.75 / 6.09 / 6.56 / 6.60 (not comparable: 20-step episodes, theirs 500)" in text
    plot_curves(runs, tmp_path / "curves.png")
    ax = saved[-1].axes[0]
    assert not [line for line in ax.get_lines() if "authors" in line.get_label()]
    assert ax.get_xlim()[1] <= 3.5  # the runs' 3 generations, not stretched to the authors' 100


def test_the_paper_episode_length_shows_the_authors_figures_the_runs_reached(tmp_path, saved):
    runs = [_run(tmp_path / "a", [1.0, 2.0, 3.0], None), _run(tmp_path / "b", [2.0, 2.0, 2.5], 500)]
    text = report_markdown(summarize(runs, robustness=False))
    assert "| 5.75 / - / - / - |" in text and "not comparable" not in text
    plot_curves(runs, tmp_path / "curves.png")
    ax = saved[-1].axes[0]
    marks = [line for line in ax.get_lines() if "authors" in line.get_label()]
    assert len(marks) == 1 and list(marks[0].get_xdata()) == [1] and ax.get_xlim()[1] <= 3.5


def test_robust_runs_are_labelled_and_their_noisy_best_columns_explained(tmp_path):
    nominal = _run(tmp_path / "a", [1.0, 2.0], 500)
    text = report_markdown(summarize([nominal], robustness=False))
    assert "sgr robust" not in text and "best of noisy scores" not in text
    robust = _run(tmp_path / "b", [1.5, 2.5], 500)
    cfg = yaml.safe_load((robust / "config.yaml").read_text())
    (robust / "config.yaml").write_text(yaml.safe_dump({**cfg, "robust": {"episodes": 4}}))
    text = report_markdown(summarize([nominal, robust], robustness=False))
    assert "| sgr robust | Walker-v0 |" in text and "best of noisy scores" in text
