"""Where each run ran, where a report's reader looks: `sgr report`'s summary.csv has a `backend`
column and report.md a "Backends" table, each run's line `backend_summary` of its segments.json
(a run resumed on another arch says so, from the generation it moved at); an older run without
segments.json says what its config.yaml recorded, and one that recorded nothing shows "-" (empty in
summary.csv). The runs and their segments.json are written by hand here."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import yaml

from evolve.report.report import write_report


def make_run(path: Path, segments: list[dict] | None = None, **cfg) -> Path:
    """A run folder as sgr writes it (config.yaml, generations.csv of 4 generations, champion.json),
    with `segments` as its segments.json (none: a run of an sgr before segments.json)."""
    path.mkdir(parents=True)
    (path / "config.yaml").write_text(yaml.safe_dump({"method": "sgr", "task": "Walker-v0", "seed": 0,
                                                      "generations": 4, "pop_size": 8, **cfg}))
    lines = ["generation,best,mean,median,n_species,total_s"]
    lines += [f"{g},{g / 2!r},0.1,0.1,1,1.0" for g in range(1, 5)]
    (path / "generations.csv").write_text("\n".join(lines) + "\n")
    (path / "champion.json").write_text(json.dumps({"fitness": 2.0}))
    if segments is not None:
        (path / "segments.json").write_text(json.dumps(segments, indent=1) + "\n")
    return path


def segment(after: int, arch: str, precision: str = "f64") -> dict:
    return {"after_generation": after, "arch": arch, "device": f"a {arch} device", "software": False,
            "precision": precision, "workers": 1, "started": "2026-12-04T10:00:00Z"}


def test_a_run_resumed_on_another_arch_says_so_in_summary_csv_and_report_md_and_an_older_run_shows_a_dash(
        tmp_path):
    """Started on the CPU, resumed after generation 2 on CUDA: "cpu, then cuda from generation 3,
    f64" (its first CUDA generation is the third). A run whose config.yaml names its arch (as an
    older sgr wrote it) and precision: "cuda, f32". A run that recorded neither: "-"."""
    runs = tmp_path / "runs"
    make_run(runs / "moved", [segment(0, "cpu"), segment(2, "cuda")])
    make_run(runs / "older-arch", seed=1, arch="cuda", precision="f32")
    make_run(runs / "older", seed=2)
    out = write_report(runs, tmp_path / "out" / "report.md", robustness=False, gallery=False)

    summary = {r["run"]: r["backend"] for r in csv.DictReader((out.parent / "summary.csv").open())}
    assert summary == {"moved": "cpu, then cuda from generation 3, f64", "older-arch": "cuda, f32",
                       "older": ""}
    text = out.read_text()
    table = text[text.index("## Backends"):].split("\n\n")[2].splitlines()
    assert table == ["| run | backend |", "|---|---|", "| moved | cpu, then cuda from generation 3, f64 |",
                     "| older | - |", "| older-arch | cuda, f32 |"]


def test_a_report_of_runs_that_recorded_no_backend_has_no_backends_table(tmp_path):
    runs = tmp_path / "runs"
    make_run(runs / "older")
    out = write_report(runs, tmp_path / "out" / "report.md", robustness=False, gallery=False)
    assert "## Backends" not in out.read_text()
    assert [r["backend"] for r in csv.DictReader((out.parent / "summary.csv").open())] == [""]
