"""`sgr sweep`: every method x task x seed of a sweep file, on this machine or a Ray cluster."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from evolve.cli.common import positive
from tsim.errors import SgrError


def register(sub) -> argparse.ArgumentParser:
    """Add `sweep` to the dispatcher's subparsers."""
    sw = sub.add_parser("sweep", help="every method x task x seed of a sweep file, resumable")
    sw.add_argument("--config", metavar="SWEEP.yaml",
                    help="methods, tasks, seeds, [configs], [overrides], [imports]: a file, or a packaged "
                         "sweep's name (paper, tiny)")
    sw.add_argument("--out", help="sweep directory (default runs/sweep-<name>-<time>)")
    sw.add_argument("--resume", metavar="DIR",
                    help="continue a sweep: finished runs are kept, the others resumed")
    sw.add_argument("--backend", choices=("local", "ray"), default="local",
                    help="local: runs on this machine; ray: runs as tasks on a Ray cluster (default local)")
    sw.add_argument("--address", metavar="ADDR",
                    help="ray backend: join this running cluster ('auto': the one on this machine); "
                         "default: start a local Ray instance")
    sw.add_argument("--parallel", type=positive(int), default=1, metavar="K",
                    help="runs at once (on each machine with --backend ray), each with CPUs / K rollout "
                         "workers (default 1)")
    sw.add_argument("--quiet", action="store_true", help="only run starts and ends, no progress lines")
    sw.set_defaults(fn=run)
    return sw


def run(args: argparse.Namespace) -> int:
    """`sgr sweep`."""
    from evolve.sweeps.sweep import LocalBackend, Sweep, run_sweep

    if args.backend == "ray":
        from evolve.rollout.ray_cluster import require_ray
        require_ray("--backend ray")  # before the sweep directory exists
    elif args.address:
        raise SgrError("--address goes with --backend ray")
    if args.resume:
        if args.config or args.out:
            raise SgrError("--resume continues a sweep with its own sweep file; drop --config and --out")
        if not Path(args.resume).exists():
            raise SgrError(f"{args.resume} does not exist")
        # its imports are trusted only with --trust-imports; held for this command (no other sweep runs it)
        sweep = Sweep.open(args.resume, lock=True)
    else:
        if not args.config:
            raise SgrError("sgr sweep needs --config SWEEP.yaml (or --resume DIR)")
        from evolve.runs.config import find_config

        config = find_config(args.config, "sweep file")  # a path, or a packaged sweep's name (paper)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out = args.out or str(Path("runs") / f"sweep-{config.stem}-{stamp}")
        # the user names this sweep file: its imports go to the run processes trusted (Sweep.trusted),
        # and nothing else does
        sweep = Sweep.create(config, out, lock=True)
        print(f"sweep directory: {out}")
    try:
        if args.backend == "ray":
            from evolve.sweeps.ray_sweep import RayBackend
            backend = RayBackend(args.parallel, address=args.address)
        else:
            backend = LocalBackend(args.parallel)
        try:
            failed = run_sweep(sweep, backend, quiet=args.quiet)
        except KeyboardInterrupt as exc:  # 130 for Ctrl-C, 143 for SIGTERM
            from evolve.runs.stops import exit_code
            return exit_code(exc)
    finally:
        sweep.unlock()
    return 1 if failed else 0
