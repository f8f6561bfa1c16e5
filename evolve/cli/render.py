"""`sgr render`: a GIF of a run's champion (its typical perturbed episode, the median of the
verdict's replays; its exact episode with --exact; or one perturbed replay), or of any body with an
open-loop gait."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from evolve.cli.common import add_noise, nonnegative, output_path, parse_body, positive
from evolve.rollout.robust import MAX_EPISODES
from tasks.cli import MAX_PIXELS
from tasks.specs import MAX_STEPS
from tsim.errors import SgrError


def register(sub) -> argparse.ArgumentParser:
    """Add `render` to the dispatcher's subparsers."""
    r = sub.add_parser("render", help="GIF of a run's champion, or of any body with an open-loop gait")
    r.add_argument("run_dir", nargs="?", metavar="RUN_DIR",
                   help="a run folder: its champion's GIF (leave out with --body)")
    r.add_argument("--task", help="with --body: the task the body is shown in (default Walker-v0)")
    r.add_argument("--body", help="rows of digits separated by commas, or a .json/.npy matrix file")
    r.add_argument("--steps", type=positive(int, MAX_STEPS),
                   help="with --body: the episode's length (default: the task's paper length)")
    r.add_argument("--out", help="GIF path, or .mp4 for an MP4 (needs pip install 'sgr[video]'); default "
                                 "RUN_DIR/champion.gif (and champion.mp4 beside it with that extra), with "
                                 "--exact RUN_DIR/champion-exact.gif, with --replay I "
                                 "RUN_DIR/champion-replayI.gif; with --body robot.gif")
    r.add_argument("--width", type=positive(int, MAX_PIXELS), default=640,
                   help="the picture's width in pixels (default 640)")
    r.add_argument("--height", type=positive(int, MAX_PIXELS), default=320,
                   help="the picture's height in pixels (default 320)")
    r.add_argument("--fps", type=positive(float, 1000), default=30.0, help="frames per second (default 30)")
    r.add_argument("--replay", type=nonnegative(int, MAX_EPISODES), metavar="I",
                   help="the champion's perturbed replay I (as sgr report replays it; 0: the exact "
                        "episode; default: the replay whose return is the median of the verdict's 20)")
    r.add_argument("--no-overlay", dest="overlay", action="store_false",
                   help="the robot alone: no line with the task, the step and the return so far")
    r.add_argument("--exact", action="store_true",
                   help="the champion's exact (noise-free) episode, to RUN_DIR/champion-exact.gif")
    add_noise(r, several=False, default=1e-3, help="the replays' action noise scale (default 1e-3)")
    r.add_argument("--noise-kind", choices=("uniform", "gaussian"), default="uniform",
                   help="the replays' noise: uniform(+-EPS) or gaussian(0, EPS) (default uniform)")
    r.add_argument("--offset", type=nonnegative(float), default=0.0,
                   help="the replays' start shifted by uniform(+-OFFSET) (evogym units, voxel 0.1)")
    r.add_argument("--cell", metavar="I,J",
                   help="a map-elites run's elite of that cell of its archive (elites.json) instead of its "
                        "champion; default --out RUN_DIR/elite-I-J.gif")
    r.add_argument("--elites", type=positive(int, 24), metavar="N",
                   help="a map-elites run's N elites chosen across its archive, the best first, side by "
                        "side in one GIF (their exact episodes); default --out RUN_DIR/elites.gif")
    r.add_argument("--every", type=positive(int, MAX_STEPS), metavar="K",
                   help="with --elites: a frame every K steps (default 4; more: a smaller GIF)")
    r.set_defaults(fn=run)
    return r


def run(args: argparse.Namespace) -> int:
    """`sgr render`."""
    from evolve.records.replay import MEDIAN, champion_gif, replay_line
    from tasks.bench import sinusoid
    from tasks.render_episode import render_episode
    from tsim.body import check_robot
    from tsim.render import VIDEO_EXTRA, video_available, write_animation

    if args.out:
        output_path(args.out)
        if Path(args.out).suffix.lower() == ".mp4" and not video_available():  # before rendering
            raise SgrError(f"--out {args.out}: writing an MP4 needs imageio's ffmpeg plugin: {VIDEO_EXTRA}")
    if args.run_dir:
        if args.task or args.body:
            raise SgrError("give either RUN_DIR or --task with --body, not both")
        if args.steps is not None:
            raise SgrError("--steps sets the length of a --body episode: a run's champion is drawn over "
                           "its run's episode")
        if args.exact and args.replay is not None:
            raise SgrError("give either --exact or --replay I, not both")
        if args.every is not None and args.elites is None:
            raise SgrError("--every sets the frames of an --elites strip: give --elites N with it")
        if args.elites is not None:
            if args.cell or args.replay is not None:
                raise SgrError("--elites shows several elites' exact episodes: leave out --cell and --replay")
            from evolve.report.archive import elite_strip

            width = args.width if args.width != 640 else 200  # (the defaults are a single champion's)
            height = args.height if args.height != 320 else 140
            frames = {"every": args.every} if args.every is not None else {}  # (else elite_strip's)
            out = elite_strip(args.run_dir, args.out, args.elites, width=width, height=height, fps=args.fps,
                              **frames)
            print(f"wrote {out}: {args.elites} elites across the archive, their exact episodes")
            return 0
        replay = 0 if args.exact else MEDIAN if args.replay is None else args.replay
        out = champion_gif(args.run_dir, args.out, width=args.width, height=args.height, fps=args.fps,
                           replay=replay, eps=args.noise, kind=args.noise_kind, offset=args.offset,
                           cell=args.cell, overlay=args.overlay)
        line = replay_line(args.run_dir, replay, args.noise, args.noise_kind, args.offset, cell=args.cell)
        mp4 = out.with_suffix(".mp4")
        also = (f" and {mp4}" if args.out is None and replay == MEDIAN and args.cell is None and mp4.is_file()
                else "")
        which = f"the elite of cell {args.cell}: " if args.cell else ""
        print(f"wrote {out}{also}: {which}{line}")
        return 0
    else:
        if args.cell or args.elites is not None:
            raise SgrError(f"{'--cell' if args.cell else '--elites'} renders elites of a map-elites run: "
                           "give RUN_DIR")
        if not (args.task and args.body):
            raise SgrError("sgr render needs RUN_DIR, or --task and --body")
        if args.replay or args.exact:
            raise SgrError(f"{'--exact' if args.exact else '--replay'} renders an episode of a run's "
                           "champion: give RUN_DIR")
        body = check_robot(parse_body(args.body))
        n_act = int(np.count_nonzero((body == 3) | (body == 4)))
        def line(t: int, total: float) -> str:
            return f"{args.task}   step {t}   return {total:.3f}"

        frames = render_episode(args.task, body, lambda t, obs: sinusoid(t, n_act), args.steps,
                                args.width, args.height, indexed=True, caption=line if args.overlay else None)
        out = write_animation(frames, args.out or "robot.gif", fps=args.fps)
    print(f"wrote {out}")
    return 0
