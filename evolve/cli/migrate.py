"""`sgr migrate RUN [--trust-pickle]`: an older sgr's pickles and champion files in today's formats
(evolve/runs/migrate.py); `sgr convert-checkpoints` is its alias."""

from __future__ import annotations

import argparse
import sys

from tsim.errors import SgrError

TRUST_HELP = "convert pickles too: loading a pickle runs any code in it; say you trust the folder"


def register(sub) -> argparse.ArgumentParser:
    """Add `migrate` and its alias `convert-checkpoints` to the dispatcher's subparsers."""
    m = sub.add_parser("migrate", help="bring an older sgr's files to today's formats: pickled "
                                       "checkpoints and task.pkl (with --trust-pickle), champion files "
                                       "in the older layout")
    m.add_argument("dir", metavar="RUN", help="a run folder, a sweep folder (an older sgr's: its runs are "
                   "recorded as the sweep's, so that sgr sweep --resume resumes them), or a folder of "
                   "champion files")
    m.add_argument("--trust-pickle", action="store_true", help=TRUST_HELP)
    m.set_defaults(fn=run)
    cc = sub.add_parser("convert-checkpoints", help="an alias of `sgr migrate`")
    cc.add_argument("dir", metavar="DIR", help="a run directory or a sweep directory")
    cc.add_argument("--trust-pickle", action="store_true", help=TRUST_HELP)
    cc.set_defaults(fn=run_alias)
    return m


def run(args: argparse.Namespace) -> int:
    """`sgr migrate`."""
    from evolve.runs.migrate import migrate
    from evolve.sweeps.sweep import record_older_sweep

    recorded = record_older_sweep(args.dir)  # an older sgr's sweep: the runs you name yours
    lines = migrate(args.dir, args.trust_pickle)
    if recorded and lines and "nothing to migrate" in lines[-1]:
        lines = []
    for line in recorded + lines:
        print(line)
    return 0


def run_alias(args: argparse.Namespace) -> int:
    """`sgr convert-checkpoints`: migrates, and says in one line (the error's, on failure) that
    it is `sgr migrate` now."""
    note = f"convert-checkpoints is an alias of: sgr migrate {args.dir}" + (
        " --trust-pickle" if args.trust_pickle else "")
    try:
        code = run(args)
    except SgrError as exc:
        raise SgrError(f"{exc} ({note})") from None
    print(f"sgr: note: {note}", file=sys.stderr)
    return code
