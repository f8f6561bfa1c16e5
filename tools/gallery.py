"""A gallery of every registered task: one GIF per task of a random robot driven open-loop, and a
contact sheet with one still per task (docs/img/tasks.png is made with it).

    python tools/gallery.py [--out runs/gallery] [--steps 200] [--seed 0] [--sheet PATH]

Each task gets its own robot: `tsim.sample_robot((5, 5), rng)` with rng seeded by (--seed, a CRC
of the task name), so a task's robot does not change when tasks are added. Actions are the open-loop
sinusoid of tasks/bench.py. Frames are 240x120, every 4th step; the still is the frame at 60 % of
the episode (episodes that end early, goal reached or unstable, are shorter).
"""

from __future__ import annotations

import argparse
import time
import zlib
from pathlib import Path

import numpy as np

WIDTH, HEIGHT, EVERY = 240, 120, 4
STILL_AT = 0.6
COLUMNS = 6
LABEL_H = 16


def task_robot(name: str, seed: int) -> np.ndarray:
    """The gallery's random 5x5 robot for task `name` (same seed and name: same robot)."""
    from tsim.sampling import sample_robot

    return sample_robot((5, 5), np.random.default_rng([seed, zlib.crc32(name.encode())]))


def task_frames(name: str, steps: int, seed: int) -> list[np.ndarray]:
    """Palette-index frames of the task's gallery robot driven by the sinusoid for `steps` steps."""
    from tasks.bench import sinusoid
    from tasks.render_episode import render_episode
    from tsim.body import build_body

    body = build_body(task_robot(name, seed))
    n_act = len(body.actuator_flat)
    return render_episode(name, body, lambda t, obs: sinusoid(t, n_act), steps, WIDTH, HEIGHT,
                          every=EVERY, indexed=True)


def contact_sheet(stills: dict[str, np.ndarray], path: str | Path, columns: int = COLUMNS) -> Path:
    """A grid PNG of palette-index stills with each task's name under its picture."""
    from PIL import Image, ImageDraw, ImageFont

    from tsim.render import PALETTE

    h, w = next(iter(stills.values())).shape
    rows = -(-len(stills) // columns)
    sheet = Image.new("RGB", (columns * w, rows * (h + LABEL_H)), "white")
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default()
    for i, (name, frame) in enumerate(stills.items()):
        x, y = (i % columns) * w, (i // columns) * (h + LABEL_H)
        sheet.paste(Image.fromarray(np.take(PALETTE, frame, axis=0).astype(np.uint8)), (x, y))
        tw = draw.textlength(name, font=font)
        draw.text((x + (w - tw) / 2, y + h + 2), name, fill="black", font=font)
    for c in range(1, columns):  # thin separators between the columns
        draw.line([(c * w, 0), (c * w, sheet.height)], fill="white", width=1)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet.quantize(colors=64, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    return path


def main(argv: list[str] | None = None) -> dict:
    """Render every task's GIF into --out and the contact sheet; prints and returns timings."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="runs/gallery", help="folder for the GIFs and the contact sheet")
    p.add_argument("--steps", type=int, default=200, help="env steps per episode")
    p.add_argument("--seed", type=int, default=0, help="robot seed (mixed with each task's name)")
    p.add_argument("--sheet", default="", help="contact sheet path (default OUT/tasks.png)")
    args = p.parse_args(argv)
    if args.steps < 1:
        p.error("--steps must be >= 1")

    from tasks.specs import TASKS
    from tsim.render import write_gif

    out = Path(args.out)
    t0 = time.perf_counter()
    stills = {}
    for name in TASKS:
        t1 = time.perf_counter()
        frames = task_frames(name, args.steps, args.seed)
        write_gif(frames, out / f"{name}.gif", fps=30.0 / EVERY)
        stills[name] = frames[min(len(frames) - 1, round(STILL_AT * (len(frames) - 1)))]
        print(f"{name:<24} {len(frames):>4} frames  {time.perf_counter() - t1:5.1f} s", flush=True)
    sheet = contact_sheet(stills, args.sheet or out / "tasks.png")
    result = {"tasks": len(stills), "seconds": round(time.perf_counter() - t0, 1), "sheet": str(sheet),
              "sheet_kb": round(sheet.stat().st_size / 1024, 1)}
    print(" ".join(f"{k}={v}" for k, v in result.items()))
    return result


if __name__ == "__main__":
    main()
