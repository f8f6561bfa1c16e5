"""The measurement docs open with the current state (what the doc is, today's figures per machine,
how to reproduce them) and keep their dated history apart (docs/history/, or below Today in
VALIDATION.md), so a newcomer finds today's figures without reading the history."""

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
DATED = re.compile(r"20\d\d-\d\d-\d\d|\bissue \d+|\b(Before|Earlier|Now)\b")


def _today(text: str) -> tuple[list[str], str]:
    """A page's `## ` headings and its first section, which must be today's state with figures
    and how to reproduce them (no dated heading)."""
    headings = re.findall(r"^## (.*)$", text, re.M)
    assert headings[0].startswith("Today"), headings[:3]
    assert not DATED.search(headings[0])
    today = text[text.index("## " + headings[0]):text.index("## " + headings[1])]
    assert "`sgr " in today or re.search(r"python (bench|studies)/", today)  # how to reproduce the figures
    assert re.search(r"\d\.\d", today)  # figures, not only words
    return headings, today


@pytest.mark.parametrize("doc", ["BENCHMARKS.md", "RESULTS.md"])
def test_a_measurement_doc_opens_with_today_and_links_to_its_dated_history_page(doc):
    """Dated history lives in docs/history/<doc>, so the page itself is today's state only."""
    text = (DOCS / doc).read_text()
    headings, _ = _today(text)
    assert not any(DATED.search(h) for h in headings), headings  # no dated entry left on the page
    assert f"(history/{doc})" in text
    history = (DOCS / "history" / doc).read_text()
    dated = re.findall(r"^## (.*)$", history, re.M)
    assert dated and DATED.search(dated[0]), dated[:2]  # newest first, each entry under its date
    assert not any(h.startswith("Today") for h in dated)
    assert f"(../{doc})" in history  # and back to today's figures


def test_validation_is_todays_page_and_its_history_holds_how_the_figures_came_to_be():
    """VALIDATION.md is today's figures in a page (no dated or per-issue section); the figures per
    data set and the changes that moved them are in history/VALIDATION.md, each section linked."""
    text = (DOCS / "VALIDATION.md").read_text()
    headings, _ = _today(text)
    assert not any(DATED.search(h) or "issue" in h for h in headings), headings
    assert len(text) < 8_000, len(text)
    history = (DOCS / "history" / "VALIDATION.md").read_text()
    sections = re.findall(r"^## (.*)$", history, re.M)
    assert sections[0].startswith("How the figures came"), sections[:2]
    for h in sections:
        assert f"(history/VALIDATION.md#{_anchor(h)})" in text, h
    assert "(../VALIDATION.md)" in history


def test_benchmarks_today_names_each_machine():
    text = (DOCS / "BENCHMARKS.md").read_text()
    today = text[:text.index("## History")]
    for machine in ("Intel Xeon", "AMD EPYC", "H200"):
        assert machine in today


def _anchor(heading: str) -> str:
    """A heading's anchor as GitHub makes it: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def broken_links(page: Path) -> list[str]:
    """The relative links of `page` whose file, or whose `#anchor` in that file, does not exist."""
    broken = []
    for target in re.findall(r"\]\((?!https?:|mailto:)([^)\s]+)\)", page.read_text()):
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if not file.exists():
            broken.append(target)
        elif anchor and file.suffix == ".md":
            if anchor not in {_anchor(h) for h in re.findall(r"^#+ (.*)$", file.read_text(), re.M)}:
                broken.append(target)
    return broken


@pytest.mark.parametrize("page", ["README.md", "history/BENCHMARKS.md", "history/RESULTS.md",
                                  "reference/tolerances.md"])
def test_every_link_of_the_docs_index_and_history_pages_leads_somewhere(page):
    """The index (docs/README.md) is links only, the moved history's relative links were rewritten, and
    every figure of the tolerances page leads to the VALIDATION.md section that states it."""
    assert not broken_links(DOCS / page), broken_links(DOCS / page)


def test_a_link_to_a_missing_file_or_heading_is_found_broken(tmp_path):
    (tmp_path / "a.md").write_text("# A\n\n## Two words\n")
    page = tmp_path / "index.md"
    page.write_text("[ok](a.md#two-words) [gone](b.md) [no heading](a.md#three) [self](#a)")
    assert broken_links(page) == ["b.md", "a.md#three", "#a"]


def figures_outside_links(table: str) -> list[str]:
    """The `bound` cells of a Markdown table that still hold a digit once their links are taken out."""
    rows = [[cell.strip() for cell in re.split(r"(?<!\\)\|", line.strip().strip("|"))]
            for line in table.splitlines() if line.startswith("| ") and "---" not in line]
    column = rows[0].index("bound")
    bare = [row[column] for row in rows[1:]]
    return [cell for cell in bare if re.search(r"\d", re.sub(r"\[[^\]]*\]\([^)]*\)", "", cell))]


def test_every_figure_of_the_tolerances_page_is_a_link():
    """A tolerance stated here is a pointer to VALIDATION.md, where it is measured, never a copy."""
    assert not figures_outside_links((DOCS / "reference" / "tolerances.md").read_text())
    table = "| what | bound |\n|---|---|\n| x | [1e-6](a.md#b), 5e-5 |"
    assert figures_outside_links(table) == ["[1e-6](a.md#b), 5e-5"]


def test_every_test_file_the_reliability_page_names_exists():
    """docs/RELIABILITY.md names, in each row, the test that checks it (under tests/evolve/ unless
    its path says otherwise): each file named is there (tests moved between folders left stale
    names once)."""
    root = DOCS.parent
    text = (DOCS / "RELIABILITY.md").read_text()
    named = set(re.findall(r"`((?:[\w/]+/)?test_\w+\.py)", text))
    assert len(named) > 30  # the page still names its tests this way
    bases = (root, root / "tests", root / "tests" / "evolve")
    missing = sorted(f for f in named if not any((base / f).is_file() for base in bases))
    assert not missing, f"docs/RELIABILITY.md names test files that do not exist: {missing}"
