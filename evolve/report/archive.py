"""A map-elites run's archive as a picture (archive.png): a heatmap of each cell's elite fitness over
the first two descriptors, with each elite's body drawn small in its cell; and the elites a report's
gallery shows, chosen across the map. Read from elites.json alone (evolve/records/elites.py).
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from evolve.records.elites import read_elites
from evolve.report.gallery import VOXEL_RGB, body_image, data_uri
from evolve.report.plots import save_png
from evolve.report.sections import Section, SectionPart, register_section
from tsim.errors import SgrError
from tsim.files import make_folder

MATERIALS = ("empty", "rigid", "soft", "horizontal actuator", "vertical actuator")  # evogym's voxel types


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
    _cell_axes(ax, extent, n_i, n_j, one_row=len(data["resolution"]) == 1)
    if bodies:
        from matplotlib.patches import Patch

        handles = [Patch(facecolor=VOXEL_RGB[k] / 255, edgecolor="0.4", label=label)
                   for k, label in enumerate(MATERIALS) if k > 0]
        fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=7, frameon=False)
    offset = data.get("score_offset")
    offset = f" (offset {offset:g})" if isinstance(offset, int | float) else ""
    ax.set_title(f"archive after generation {data['generation']}: {len(data['elites'])} elites, coverage "
                 f"{data['coverage']:.1%}, QD score {data['qd_score']:.3f}{offset}", fontsize=9, pad=18)
    fig.tight_layout(rect=(0, 0.05 if bodies else 0, 1, 1))
    return save_png(fig, out or Path(run_dir) / "archive.png")


def _cell_axes(ax, extent: tuple[float, ...], n_i: int, n_j: int, one_row: bool) -> None:
    """Cell indices on the top and right axes, at each cell's centre (`sgr render RUN --cell I,J`)."""
    def ticks(lo: float, hi: float, n: int) -> tuple[np.ndarray, int]:
        step = max(1, int(np.ceil(n / 12)))  # at most ~12 labels
        idx = np.arange(0, n, step)
        return lo + (idx + 0.5) * (hi - lo) / n, idx

    top = ax.secondary_xaxis("top")
    at, idx = ticks(extent[0], extent[1], n_i)
    top.set_ticks(at, labels=[str(i) for i in idx], fontsize=7)
    top.set_xlabel("cell index i", fontsize=7)
    if not one_row:
        right = ax.secondary_yaxis("right")
        at, idx = ticks(extent[2], extent[3], n_j)
        right.set_ticks(at, labels=[str(j) for j in idx], fontsize=7)
        right.set_ylabel("cell index j", fontsize=7)


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


def elite_strip(run_dir: str | Path, out: str | Path | None = None, n: int = 6, *, width: int = 200,
                height: int = 140, fps: float = 20.0, every: int = 4) -> Path:
    """One GIF of `n` elites chosen across the map (`spread_elites`, the best first) side by side,
    each its exact episode (a frame every `every` steps; one that ends early holds its last frame),
    captioned with its cell and return so far. Default `out`: RUN/elites.gif. Returns its path."""
    from evolve.records.champion import precision_of, read_champion
    from tasks.render_episode import render_episode
    from tsim.render import write_animation

    panels = []
    for e in spread_elites(run_dir, n):
        cell = tuple(e["cell"])
        champ, body, ctrl = read_champion(run_dir, cell)
        label = ",".join(map(str, cell))

        def line(t: int, total: float, label: str = label) -> str:
            return f"cell {label}  {total:.2f}"

        panels.append(render_episode(champ["task"], body, lambda t, obs, ctrl=ctrl: ctrl.act(obs),
                                     champ["episode_steps"], width, height, every=every, indexed=True,
                                     precision=precision_of(champ), caption=line))
    if not panels:
        raise SgrError(f"{run_dir}: the archive has no elite to show")
    length = max(len(p) for p in panels)
    gap = np.zeros((height, 2), dtype=panels[0][0].dtype)  # PALETTE 0: the background
    frames = []
    for k in range(length):
        row = []
        for p in panels:
            row += [p[min(k, len(p) - 1)], gap]
        frames.append(np.concatenate(row[:-1], axis=1))
    return write_animation(frames, out or Path(run_dir) / "elites.gif", fps=fps)


def write_archives(runs: dict[str, Path], folder: Path, n: int = 6) -> list[dict]:
    """For each map-elites run of `runs` (name -> run folder; those with elites.json), its archive
    picture <name>-archive.png and the bodies of `n` elites chosen across the map
    (<name>-elite-I-J.png) in `folder`; returns one entry per run: name, archive and elites (each
    with its cell, fitness, descriptors and body picture)."""
    import imageio.v3 as iio

    from evolve.records.elites import elites_file
    from evolve.records.files import atomic_write

    out = []
    for name, run in runs.items():
        if elites_file(run) is None:
            continue
        make_folder(folder, folder.parent)  # a planted link named archives/ is refused, not followed
        safe = str(name).replace("/", "-")
        png = plot_archive(run, folder / f"{safe}-archive.png")
        shown = []
        for e in spread_elites(run, n):
            cell = "-".join(map(str, e["cell"]))
            body = folder / f"{safe}-elite-{cell}.png"
            atomic_write(body, iio.imwrite("<bytes>", body_image(np.asarray(e["champion"]["body"])),
                                           extension=".png"), inside=folder)
            shown.append({"cell": e["cell"], "fitness": float(e["champion"]["fitness"]),
                          "measures": e["measures"], "body": body})
        out.append({"name": str(name), "archive": png, "elites": shown})
    return out


def _caption(e: dict) -> str:
    measures = ", ".join(f"{k} {v:.2f}" for k, v in e["measures"].items())
    return f"cell {','.join(map(str, e['cell']))} · fitness {e['fitness']:.3f} · {measures}"


def archives_markdown(entries: list[dict], base: Path) -> str:
    """report.md's section on the map-elites runs' archives (paths relative to `base`)."""
    if not entries:
        return ""
    lines = ["", "## Archives (map-elites)", "",
             "Each map-elites run's archive: each cell's elite fitness, its body drawn small; then "
             "elites chosen across the map (`sgr render RUN --cell I,J` renders any of them).", ""]
    for a in entries:
        lines += [f"### {a['name']}", "", f"![archive of {a['name']}]({a['archive'].relative_to(base)})", ""]
        lines += [f"- {_caption(e)}: ![body]({e['body'].relative_to(base)})" for e in a["elites"]] + [""]
    return "\n".join(lines)


def archives_html(entries: list[dict]) -> list[str]:
    """report.html's parts on the archives, images inlined as data URIs."""
    if not entries:
        return []
    parts = ["<h2>Archives (map-elites)</h2><p>Each cell's elite fitness, its body drawn small; below, "
             "elites chosen across the map.</p>"]
    for a in entries:
        name = html.escape(a["name"])
        parts.append(f"<h3>{name}</h3><img alt='archive of {name}' src='{data_uri(a['archive'])}'"
                     " width='100%'><div class='gallery'>")
        parts += [f"<figure><img alt='{name} elite' src='{data_uri(e['body'])}'>"
                  f"<figcaption>{html.escape(_caption(e))}</figcaption></figure>" for e in a["elites"]]
        parts.append("</div>")
    return parts


def _archives_part(rows: list[dict], runs: list[Path], folder: Path, pool) -> SectionPart:
    entries = write_archives({r["run"]: r["path"] for r in rows}, folder / "archives")
    return SectionPart(archives_markdown(entries, folder), archives_html(entries))


register_section(Section("archives", part=_archives_part, order=30))
