"""`sgr decode`: a run's champion genome decoded at another body size, as a champion folder."""

from __future__ import annotations

import argparse

from evolve.cli.common import output_path, parse_shape


def register(sub) -> argparse.ArgumentParser:
    """Add `decode` to the dispatcher's subparsers."""
    d = sub.add_parser("decode", help="a run's champion genome decoded at another body size (sgr runs)")
    d.add_argument("run_dir", metavar="RUN", help="a finished sgr run folder")
    d.add_argument("--shape", required=True, metavar="RxC", help="the body grid, rows x columns (e.g. 10x10)")
    d.add_argument("--out", help="the folder to write champion.json in (default: RUN-RxC beside RUN); "
                                 "load_champion, sgr render and sgr's replays read it as any run's")
    d.set_defaults(fn=run)
    return d


def run(args: argparse.Namespace) -> int:
    """`sgr decode`."""
    from evolve.cli.common import resume_dir
    from evolve.records.decode import write_decoded
    from evolve.records.rundir import RunDir

    shape = parse_shape(args.shape)
    if args.out:
        from pathlib import Path

        from tsim.errors import SgrError

        if args.out.endswith(".json") and Path(args.out).name != "champion.json":
            raise SgrError(f"--out {args.out}: give a folder, or a path ending in champion.json (the name "
                           "load_champion and sgr render read)")
        output_path(args.out, folder=not args.out.endswith(".json"))
    out = write_decoded(resume_dir(args.run_dir), shape, args.out)
    champ = RunDir(out).champion()
    print(f"wrote {out / 'champion.json'}: {shape[0]}x{shape[1]} body, fitness {champ['fitness']:.4f}; "
          f"sgr render {out}")
    return 0
