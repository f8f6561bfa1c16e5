"""Time headless rendering of one episode (simulation included), then the GIF write.

    python bench/render_bench.py [--task Thrower-v0] [--steps 300] [--width 640] [--height 320]
                                 [--every 1] [--rgb] [--gif /tmp/render_bench.gif]

Acceptance target: a 300-step Thrower-v0 episode at 640x320 in <= 10 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

BODY = [[3, 3, 3, 3, 3],
        [3, 1, 1, 1, 3],
        [3, 4, 2, 4, 3],
        [3, 3, 0, 3, 3],
        [3, 3, 0, 3, 3]]


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--task", default="Thrower-v0")
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=320)
    p.add_argument("--every", type=int, default=1, help="render every k-th step")
    p.add_argument("--rgb", action="store_true", help="RGB frames instead of palette-index frames")
    p.add_argument("--gif", default="", help="also write (and time) a GIF here")
    args = p.parse_args(argv)

    t_import = time.perf_counter()
    from tasks.bench import sinusoid
    from tasks.render_episode import render_episode
    from tsim.body import build_body
    from tsim.render import write_gif

    body = build_body(np.array(BODY))
    n_act = body.n_actuators
    t0 = time.perf_counter()
    frames = render_episode(args.task, body, lambda t, obs: sinusoid(t, n_act), args.steps,
                            args.width, args.height, every=args.every, indexed=not args.rgb)
    episode_s = time.perf_counter() - t0
    result = {"task": args.task, "steps": args.steps, "size": f"{args.width}x{args.height}",
              "every": args.every, "rgb": args.rgb, "frames": len(frames), "episode_s": round(episode_s, 3),
              "frames_per_s": round(len(frames) / episode_s, 1),
              "import_s": round(t0 - t_import, 3)}
    if args.gif:
        t1 = time.perf_counter()
        write_gif(frames, args.gif, fps=30.0 / args.every)
        result["gif_s"] = round(time.perf_counter() - t1, 3)
        result["gif"] = args.gif
    print(" ".join(f"{k}={v}" for k, v in result.items()))
    return result


if __name__ == "__main__":
    main()
