"""The measurement docs open with the current state (what the doc is, today's figures per machine,
how to reproduce them) and keep their dated history below it, so a newcomer finds today's figures
without reading the history."""

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
DATED = re.compile(r"20\d\d-\d\d-\d\d|\bissue \d+|\b(Before|Earlier|Now)\b")


@pytest.mark.parametrize("doc", ["BENCHMARKS.md", "RESULTS.md", "VALIDATION.md"])
def test_a_measurement_doc_opens_with_today_and_keeps_its_history_below(doc):
    text = (DOCS / doc).read_text()
    headings = re.findall(r"^## (.*)$", text, re.M)
    assert headings[0].startswith("Today"), headings[:3]
    assert not DATED.search(headings[0])
    today = text[text.index("## " + headings[0]):text.index("## " + headings[1])]
    assert "`sgr " in today or re.search(r"python (bench|studies)/", today)  # how to reproduce the figures
    assert re.search(r"\d\.\d", today)  # figures, not only words
    later = headings[1:]
    assert any(h.startswith(("History", "How the figures came")) for h in later[:1]), later[:2]
    first_dated = next((i for i, h in enumerate(headings) if DATED.search(h)), len(headings))
    assert first_dated >= 2  # every dated heading comes after today's section and the history's


def test_benchmarks_today_names_each_machine():
    text = (DOCS / "BENCHMARKS.md").read_text()
    today = text[:text.index("## History")]
    for machine in ("Intel Xeon", "AMD EPYC", "H200"):
        assert machine in today
