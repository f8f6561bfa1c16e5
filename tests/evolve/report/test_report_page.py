"""report.html reads at a normal size: its text at 15 px or more, its curves' text as large on the
page as a plain matplotlib figure's, its gallery robots 480 pixels wide, and no status line unless
an image failed (a third-week user found small curves, tiny robots and a stray "5 of 5 images
loaded" line). The page in a real browser: tests/evolve/report/test_report_html.py."""

from __future__ import annotations

import inspect
import re

import pytest

from evolve.report import gallery
from evolve.report.report import CURVES_DPI, PAGE_PX, plot_curves


def test_the_pages_text_is_at_least_15_pixels():
    sizes = [int(x) for x in re.findall(r"font-size:(\d+)px", gallery.STYLE)]
    assert sizes and min(sizes) >= 14 and re.search(r"body\{[^}]*font-size:1[6-9]px", gallery.STYLE)
    assert min(s for s in sizes if s != 14) >= 15  # 14: the status line, shown only on a failure


def test_the_gallery_draws_its_robots_480_pixels_wide():
    params = inspect.signature(gallery.write_gallery).parameters
    assert params["width"].default >= 480 and params["height"].default >= 240


def test_the_status_line_is_hidden_unless_an_image_failed():
    page = gallery.report_html("# Results\n", _png(), [])
    assert "<p id='images' hidden></p>" in page and "s.hidden=ok==im.length" in page
    assert "images not checked" not in page


@pytest.mark.slow
def test_the_curves_text_is_scaled_to_read_at_the_pages_width(tmp_path, monkeypatch):
    """Three panels a row are drawn 1,980 px wide and shown 1,200 wide: their text is drawn at
    10 pt x 1980 / 1200 so that it shows as 10 pt."""
    from matplotlib.figure import Figure

    from tests.evolve.report.test_report_groups import make_run

    saved: list[Figure] = []
    real = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: (saved.append(self), real(self, *a, **k))[1])
    run = make_run(tmp_path / "r", best=(1.0, 2.0, 3.0))
    plot_curves([run], tmp_path / "curves.png")
    fig = saved[-1]
    panels = len(fig.axes)
    title = fig.axes[0].title.get_fontsize()
    assert title == pytest.approx(12 * max(1.0, 6 * panels * CURVES_DPI / PAGE_PX))  # "large": 1.2 x


def _png():
    from pathlib import Path

    return Path(__file__).resolve().parents[3] / "docs" / "img" / next(
        p.name for p in (Path(__file__).resolve().parents[3] / "docs" / "img").glob("*.png"))
