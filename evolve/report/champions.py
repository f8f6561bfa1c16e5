"""The report's sections on where each champion came from: its body ("Champion bodies") and the
backends its run ran on ("Backends"), each one `register_section` (evolve/report/sections.py).

Their values are on every run's row already (`evolve.report.report.summarize` measures the body
and reads segments.json): these sections only write them out, first among the sections.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

from evolve.report.sections import Section, SectionPart, register_section


def bodies_markdown(rows: list[dict]) -> str:
    """report.md's "Champion bodies": each run's champion body measured (`champion_body_measures`)
    and its final population's body diversity; "" when no run has either."""
    from evolve.methods.body_measures import material_shares

    shown = [r for r in rows if "width" in r or "body_diversity" in r]
    if not shown:
        return ""
    out = io.StringIO()
    out.write("\n## Champion bodies\n\nEach run's champion body (docs/EVOLVE.md \"Body measures\"): the "
              "rows x columns of its bounding box, the share of the box it fills, its materials' shares of "
              "its voxels (rigid / soft / horizontal / vertical actuators), its left-right and "
              "top-bottom symmetry (1: its own mirror image), its irregularity (the compressed size of its "
              "material grid, 0 for one material throughout); and the body diversity of the run's last "
              "generation (the mean pairwise distance per cell of its valid bodies; - for runs made before "
              "it was recorded).\n\n")
    out.write("| run | body | fill | rigid / soft / h / v | symmetry lr | symmetry tb | irregularity | "
              "final diversity |\n" + "|---" * 8 + "|\n")
    for r in sorted(shown, key=lambda r: r["run"]):
        materials = material_shares(r) or "-"
        fill = f"{100 * r['fill']:.0f} %" if "fill" in r else "-"
        cells = (["-"] * 6 if "width" not in r else
                 [f"{r['height']}x{r['width']}", fill, materials,
                  f"{r['symmetry_lr']:.2f}", f"{r['symmetry_tb']:.2f}", str(r["irregularity"])])
        diversity = f"{r['body_diversity']:.3f}" if "body_diversity" in r else "-"
        out.write(f"| {r['run']} | " + " | ".join(cells) + f" | {diversity} |\n")
    return out.getvalue()


def backends_markdown(rows: list[dict]) -> str:
    """report.md's "Backends": where each run ran (`evolve.records.segments.backend_summary`), so
    that a run resumed on another arch says so; "" when no run recorded it."""
    if not any(r.get("backend") for r in rows):
        return ""
    return ("\n## Backends\n\nWhere each run ran (its segments.json): the arch it started on, each "
            "arch a resume moved it to and from which generation, and its precision; - for runs made "
            "before this was recorded.\n\n| run | backend |\n|---|---|\n"
            + "".join(f"| {r['run']} | {r.get('backend') or '-'} |\n"
                      for r in sorted(rows, key=lambda r: r["run"])))


def _bodies_part(rows: list[dict], runs: list[Path], folder: Path, pool: Sequence[str]) -> SectionPart:
    return SectionPart(bodies_markdown(rows))


def _backends_part(rows: list[dict], runs: list[Path], folder: Path, pool: Sequence[str]) -> SectionPart:
    return SectionPart(backends_markdown(rows))


register_section(Section("champion bodies", part=_bodies_part, order=1))
register_section(Section("backends", part=_backends_part, order=2))
