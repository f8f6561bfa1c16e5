"""What a report shows besides numbers: a gallery of champions and one self-contained report.html.

The gallery holds, per (method, task), the champion of the best seed (highest recorded fitness) as
a GIF of its episode and a picture of its body. report.html inlines report.md's tables, the curves
and the gallery as data URIs, so the one file opens anywhere, offline, and can be mailed or
archived beside a paper.
"""

from __future__ import annotations

import base64
import html
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from tsim.render import BACKGROUND, BLUES, GRID, ORANGES, RIGID_COLOR, SOFT_COLOR

# evogym's voxel types 0-4: empty, rigid, soft, horizontal and vertical actuator
VOXEL_RGB = np.array([BACKGROUND, RIGID_COLOR, SOFT_COLOR, ORANGES[60], BLUES[60]], dtype=np.uint8)


def body_image(body: np.ndarray, cell: int = 20) -> np.ndarray:
    """(H*cell+1, W*cell+1, 3) uint8 picture of a body matrix (row 0 = top), one colour per voxel
    type as in the renderer, with grid lines."""
    body = np.asarray(body, dtype=np.int64)
    img = np.repeat(np.repeat(VOXEL_RGB[body], cell, axis=0), cell, axis=1)
    h, w = body.shape
    out = np.empty((h * cell + 1, w * cell + 1, 3), dtype=np.uint8)
    out[:-1, :-1] = img
    out[::cell, :] = GRID
    out[:, ::cell] = GRID
    return out


def champion_figure(row: dict) -> float:
    """A summary row's champion figure: its headline (the held-out mean return under the run's
    noise, evolve/records/verdict.py), or for a record without one its recorded fitness."""
    return row.get("headline", row["champion_fitness"])


def gallery_entries(rows: Sequence[dict], runs: Sequence[Path] | Mapping[str, Path]) -> list[dict]:
    """Per (method, task) (the report's groups), the summary row and run directory of the seed with
    the best champion figure (its headline, else its recorded fitness; ties: the lower seed),
    sorted by method and task; `runs` by the rows' `run` names (a list: by folder name)."""
    by_name = dict(runs) if isinstance(runs, Mapping) else {d.name: d for d in runs}
    best: dict[tuple[str, str], dict] = {}
    for r in rows:
        f = champion_figure(r) if "champion_fitness" in r else None
        d = by_name.get(r["run"])
        if f is None or not math.isfinite(f) or d is None or not (d / "champion.json").is_file():
            continue
        key = (r["method"], r["task"])
        held = best.get(key)
        if held is None or (f, -int(r["seed"] or 0)) > (champion_figure(held), -int(held["seed"] or 0)):
            best[key] = r
    return [{"row": best[k], "run": by_name[best[k]["run"]]} for k in sorted(best)]


def write_gallery(entries: Sequence[dict], folder: Path, *, width: int = 480, height: int = 240,
                  every: int = 10, fps: float = 8.0) -> list[dict]:
    """Write <run>.gif (every `every`-th step of the champion's typical episode, the median of the
    verdict's replays: `champion_gif`) and <run>-body.png into
    `folder` for each entry; returns the entries with `gif` and `body` paths added."""
    import imageio.v3 as iio

    from evolve.records.champion import read_champion
    from evolve.records.files import atomic_write
    from evolve.records.replay import champion_gif
    from tsim.files import make_folder

    make_folder(folder, folder.parent)  # a planted link named gallery/ is refused, not followed
    out = []
    for e in entries:
        name = str(e["row"].get("run") or e["run"].name).replace("/", "-")  # unique among the report's runs
        gif = champion_gif(e["run"], folder / f"{name}.gif", width=width, height=height, fps=fps,
                           every=every)
        _, body, _ = read_champion(e["run"])
        png = folder / f"{name}-body.png"
        atomic_write(png, iio.imwrite("<bytes>", body_image(body), extension=".png"),  # whole or not at all
                     inside=folder)
        out.append({**e, "gif": gif, "body": png})
    return out


def data_uri(path: Path, mime: str = "image/png") -> str:
    """A file's bytes as a data URI (report.html inlines every image)."""
    return f"data:{mime};base64,{base64.b64encode(Path(path).read_bytes()).decode()}"


def _inline(text: str) -> str:
    """One line of our markdown as HTML: escaped, **bold** and *emphasis*."""
    s = html.escape(text, quote=False)
    s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
    return re.sub(r"\*(.+?)\*", r"<em>\1</em>", s)


def markdown_html(text: str) -> str:
    """HTML of report.md: headings, paragraphs and pipe tables (all that report.md uses)."""
    out: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            out.append(f"<h{level}>{_inline(line[level:].strip())}</h{level}>")
        elif line.startswith("|"):
            table = []
            while i < len(lines) and lines[i].startswith("|"):
                table.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
                i += 1
            head, body = table[0], [r for r in table[1:] if not all(set(c) <= {"-"} for c in r)]
            out.append("<table><thead><tr>" + "".join(f"<th>{_inline(c)}</th>" for c in head)
                       + "</tr></thead><tbody>"
                       + "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>"
                                 for r in body) + "</tbody></table>")
            continue
        elif line.strip():
            para = [line]
            while i + 1 < len(lines) and lines[i + 1].strip() and lines[i + 1][0] not in "#|":
                i += 1
                para.append(lines[i])
            out.append(f"<p>{_inline(' '.join(para))}</p>")
        i += 1
    return "\n".join(out)


STYLE = """body{font-family:system-ui,sans-serif;font-size:16px;line-height:1.45;margin:2em auto;
max-width:1200px;padding:0 1em;color:#222}
table{border-collapse:collapse;font-size:15px;margin:1em 0}th,td{border:1px solid #ccc;padding:4px 8px}
th{background:#f2f2f2}td{text-align:right}td:first-child,td:nth-child(2){text-align:left}
.gallery{display:flex;flex-wrap:wrap;gap:20px}figure{margin:0;border:1px solid #ddd;padding:10px}
figure img{display:block;margin-bottom:6px}img.body{width:200px;image-rendering:pixelated}
figcaption{font-size:15px;max-width:480px}
#images{color:#cf222e;font-size:14px}"""

# after loading, the page checks that each of its images decoded (its data-ok and data-total, read by
# the test); it says so on the page only where one did not (a line in red), never when all did
CHECK = """<script>window.addEventListener('load',function(){var im=document.images,ok=0;
for(var i=0;i<im.length;i++){if(im[i].complete&&im[i].naturalWidth>0){ok++;}}
var s=document.getElementById('images');s.textContent=ok+' of '+im.length+' images loaded';
s.dataset.ok=ok;s.dataset.total=im.length;s.hidden=ok==im.length;});</script>"""


def report_html(markdown: str, curves: Path, gallery: Sequence[dict], extra: Sequence[str] = (),
                title: str = "sgr report") -> str:
    """The whole report as one HTML page with every image inlined (no network, no other file);
    `extra`: more of its HTML, after the gallery (map-elites archives: evolve/report/archive.py)."""
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             f"<style>{STYLE}</style></head><body>", markdown_html(markdown),
             "<h2>Curves</h2>", f"<img alt='curves' src='{data_uri(curves, 'image/png')}' width='100%'>"]
    if gallery:
        parts.append("<h2>Champions</h2><p>Per method and task, the seed with the best champion: "
                     "its body (orange: horizontal actuator, blue: vertical, dark: rigid, grey: soft) "
                     "and its typical episode (the median of 20 replays under ±0.001 action noise)."
                     "</p><div class='gallery'>")
        for e in gallery:
            r, name = e["row"], html.escape(e["run"].name)
            parts.append(
                f"<figure><img alt='{name} episode' src='{data_uri(e['gif'], 'image/gif')}'>"
                f"<img alt='{name} body' class='body' src='{data_uri(e['body'], 'image/png')}'>"
                f"<figcaption>{html.escape(str(r['method']))} · {html.escape(str(r['task']))} · seed "
                f"{r['seed']} · {_figure_caption(r)}{_verdict_caption(r)}"
                f"{_body_caption(r)}</figcaption></figure>")
        parts.append("</div>")
    parts += list(extra)
    parts += ["<p id='images' hidden></p>", CHECK, "</body></html>"]
    return "\n".join(parts)


def _body_caption(row: dict) -> str:
    """"<br>body 5x5, symmetry lr 1.00 tb 0.40, irregularity 9, actuators 48 %", its fill and
    materials ("fill 80 %, rigid / soft / h / v 10 / 42 / 24 / 24 %") and the final population's body
    diversity, where the report measured them (evolve/methods/body_measures.py)."""
    from evolve.methods.body_measures import describe, material_shares

    parts = [f"body {describe(row)}"] if "width" in row else []
    if "fill" in row and (shares := material_shares(row)) is not None:
        parts.append(f"fill {100 * row['fill']:.0f} %, rigid / soft / h / v {shares}")
    if "body_diversity" in row:
        parts.append(f"final diversity {row['body_diversity']:.3f}")
    return "<br>" + html.escape(" · ".join(parts)) if parts else ""


def _figure_caption(row: dict) -> str:
    """"return 0.412" (its headline, evolve/records/verdict.py) or "fitness 0.412" (a record without one)."""
    if "headline" in row:
        return f"return {row['headline']:.3f}"
    return f"fitness {row['champion_fitness']:.3f}"


def _verdict_caption(row: dict) -> str:
    """" · holds" or " · knife-edge" (evolve/records/verdict.py), where the report judged the row."""
    return f" · {row['verdict']}" if row.get("verdict") else ""
