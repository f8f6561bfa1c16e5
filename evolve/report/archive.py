"""A map-elites run's archive as a picture (archive.png): a heatmap of each cell's elite fitness over
the first two descriptors, with each elite's body drawn small in its cell; and the elites a report's
gallery shows, chosen across the map. Read from elites.json alone (evolve/records/elites.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from evolve.records.elites import read_elites
from evolve.report.gallery import body_image
from evolve.report.plots import save_png


def archive_grid(data: dict) -> tuple[np.ndarray, dict[tuple[int, int], dict]]:
    """The (cells of descriptor 1, cells of descriptor 2) grid of elite fitness (NaN: empty) and the
    elite drawn in each (i, j); with more than two descriptors a cell shows the best elite over the
    others, with one a single row."""
    res = list(data["resolution"]) + [1]
    grid = np.full((res[0], res[1]), np.nan)
    shown: dict[tuple[int, int], dict] = {}
    for e in data["elites"]:
        cell = list(e["cell"]) + [0]
        ij = (int(cell[0]), int(cell[1]))
        fit = float(e["champion"]["fitness"])
        if np.isnan(grid[ij]) or fit > grid[ij]:
            grid[ij], shown[ij] = fit, e
    return grid, shown


def plot_archive(run_dir: str | Path, out: str | Path | None = None, bodies: bool = True) -> Path:
    """archive.png (default RUN/archive.png): the heatmap, each cell's body drawn small over it when
    `bodies`; titled with the coverage and the QD score. Returns the PNG path."""
    data = read_elites(run_dir)
    grid, shown = archive_grid(data)
    names = list(data["descriptors"]) + [""]
    ranges = [list(r) for r in data["ranges"]] + [[0.0, 1.0]]
    n_i, n_j = grid.shape
    fig = Figure(figsize=(min(12, 2 + 0.6 * n_i), min(10, 1.5 + 0.6 * n_j)))
    ax = fig.add_subplot(1, 1, 1)
    extent = (ranges[0][0], ranges[0][1], ranges[1][0], ranges[1][1])
    img = ax.imshow(grid.T, origin="lower", extent=extent, aspect="auto", cmap="viridis")
    fig.colorbar(img, ax=ax, label="elite fitness")
    if bodies:
        wi, wj = (extent[1] - extent[0]) / n_i, (extent[3] - extent[2]) / n_j
        for (i, j), e in shown.items():
            pic = body_image(np.asarray(e["champion"]["body"]), cell=6)
            x0, y0 = extent[0] + i * wi, extent[2] + j * wj
            ax.imshow(pic, extent=(x0 + 0.15 * wi, x0 + 0.85 * wi, y0 + 0.15 * wj, y0 + 0.85 * wj),
                      interpolation="nearest", aspect="auto")
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1] or "")
    ax.set_title(f"archive after generation {data['generation']}: {len(data['elites'])} elites, coverage "
                 f"{data['coverage']:.1%}, QD score {data['qd_score']:.3f}", fontsize=9)
    fig.tight_layout()
    return save_png(fig, out or Path(run_dir) / "archive.png")


def spread_elites(run_dir: str | Path, n: int = 6) -> list[dict]:
    """Up to `n` elites chosen across the map for a gallery: the best one, then each next the elite
    farthest (in cells) from those chosen (ties: the fitter), so the gallery spans the archive."""
    elites = sorted(read_elites(run_dir)["elites"], key=lambda e: -float(e["champion"]["fitness"]))
    chosen: list[dict] = []
    for _ in range(min(n, len(elites))):
        def gap(e: dict) -> float:
            return min((float(np.abs(np.subtract(e["cell"], c["cell"])).sum()) for c in chosen),
                       default=0.0)
        rest = [e for e in elites if e not in chosen]
        chosen.append(max(rest, key=gap) if chosen else rest[0])
    return chosen
