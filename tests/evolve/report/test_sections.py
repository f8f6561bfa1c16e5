"""A report section is one module and one registration (evolve/report/sections.py): the example of
its docstring, registered, adds its column to summary.csv and its table to report.md and report.html,
and leaves the report as it was once it is gone."""

from __future__ import annotations

import csv

import pytest

from evolve.report import sections
from evolve.report.report import write_report


@pytest.fixture
def speed_section():
    """The module docstring's example section, registered for the test alone."""
    code = sections.__doc__.split("A section of your own:", 1)[1]
    namespace: dict = {}
    exec("\n".join(line[4:] for line in code.splitlines()), namespace)  # noqa: S102 (sgr's own docstring)
    assert "speed" in sections.SECTIONS
    yield sections.SECTIONS["speed"]
    sections.SECTIONS.pop("speed")


def test_a_registered_section_adds_its_column_and_its_part(sgr_run, tmp_path, speed_section):
    out = write_report([sgr_run], tmp_path / "with" / "report.md", robustness=False, gallery=False)
    row = next(csv.DictReader((out.parent / "summary.csv").open()))
    assert float(row["s_per_episode"]) > 0
    text = out.read_text()
    assert "## Speed" in text and f"| {row['run']} | {float(row['s_per_episode']):.4f} |" in text
    assert "<h2>Speed</h2>" in (out.parent / "report.html").read_text()


def test_without_it_the_report_has_neither(sgr_run, tmp_path):
    out = write_report([sgr_run], tmp_path / "without" / "report.md", robustness=False, gallery=False)
    assert "s_per_episode" not in (out.parent / "summary.csv").read_text()
    assert "## Speed" not in out.read_text()
    assert list(sections.SECTIONS) == ["champion bodies", "backends", "quality diversity", "behaviour",
                                       "archives"]


def test_the_guides_example_is_the_one_tested_here():
    """docs/EXTENDING.md shows this module docstring's example, the one the tests above run."""
    from pathlib import Path

    code = sections.__doc__.split("A section of your own:", 1)[1].strip("\n")
    example = "\n".join(line[4:] for line in code.splitlines())
    guide = (Path(__file__).resolve().parents[3] / "docs" / "EXTENDING.md").read_text()
    assert f"# speed.py: sgr report runs/ --import speed.py\n{example}\n```" in guide
