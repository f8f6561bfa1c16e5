"""The report's sections beyond its frame: each one module and one `register_section` call.

`sgr report` (evolve/report/report.py, the frame) writes the results table, the groups, the tests
between methods, each champion under noise, the champion bodies and the backends. A section adds
its own part: values on each run's row (and columns of summary.csv), and a part of report.md and
report.html, with any pictures it draws. The built-in ones: "champion bodies" and "backends"
(evolve/report/champions.py), "quality diversity" and "behaviour" (evolve/report/qd.py) and
"archives" (evolve/report/archive.py). A section of your own:

    from evolve.report.sections import Section, SectionPart, register_section

    def speed_row(run_dir, generations, replayed):          # a value per run, from its files
        return {"s_per_episode": float(generations["sim_s"][-1] / generations["episodes"][-1])}

    def speed_part(rows, runs, folder, pool):               # report.md's text (and report.html's)
        lines = [f"| {r['run']} | {r['s_per_episode']:.4f} |\\n" for r in rows if "s_per_episode" in r]
        return SectionPart("\\n## Speed\\n\\n| run | s / episode |\\n|---|---|\\n" + "".join(lines))

    register_section(Section("speed", columns=("s_per_episode",), row=speed_row, part=speed_part))
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class SectionPart:
    """What a section adds to the report: its report.md text, and report.html's parts (None: the
    page shows the text itself)."""

    markdown: str = ""
    html: list[str] | None = None


@dataclass(frozen=True)
class Section:
    """A part of the report.

    Args:
        name: what it is called (registering a name again replaces it).
        columns: summary.csv's columns it fills, written where some row has the first of them.
        row: (run folder, its generations.csv columns, whether the report replayed its champion)
            -> values for the run's row; {} for a run it has nothing to say about.
        part: (the rows, the run folders, the report's folder, the settings pooled) -> its part of
            report.md and report.html; it may draw pictures into the report's folder.
        order: where it appears among the sections (lower first; sgr's own: 1 to 30).
    """

    name: str
    columns: tuple[str, ...] = ()
    row: Callable[[Path, dict[str, np.ndarray], bool], dict] | None = None
    part: Callable[[list[dict], list[Path], Path, Sequence[str]], SectionPart] | None = None
    order: int = 50


SECTIONS: dict[str, Section] = {}


def register_section(section: Section) -> Section:
    """Add `section` to every report from now on: sections appear by their `order`, then in the
    order they were registered (sgr's own: champion bodies 1, backends 2, quality diversity 10,
    behaviour 20, archives 30; evolve/report/report.py imports their modules, which registers them)."""
    SECTIONS.pop(section.name, None)
    SECTIONS[section.name] = section
    ranked = sorted(enumerate(SECTIONS.values()), key=lambda kv: (kv[1].order, kv[0]))
    SECTIONS.clear()
    SECTIONS.update((s.name, s) for _, s in ranked)
    return section
