"""`sgr convert-checkpoints`: an older sgr's pickled checkpoints made JSON checkpoints."""

from __future__ import annotations

import argparse

from tsim.errors import SgrError


def register(sub) -> argparse.ArgumentParser:
    """Add `convert-checkpoints` to the dispatcher's subparsers."""
    cc = sub.add_parser("convert-checkpoints",
                        help="turn an older sgr's pickles (checkpoints gen-*.pkl, a script's task.pkl) "
                             "into data files (JSON checkpoints, task.json)")
    cc.add_argument("dir", metavar="DIR", help="a run directory or a sweep directory")
    cc.add_argument("--trust-pickle", action="store_true",
                    help="required: loading a pickle runs any code in it; say you trust the folder")
    cc.set_defaults(fn=run)
    return cc


def run(args: argparse.Namespace) -> int:
    """`sgr convert-checkpoints`."""
    from evolve.runs.legacy import convert_run, convert_task, run_dirs
    from tasks.registry import imports_trusted, trust_imports

    if not args.trust_pickle:
        raise SgrError("an older sgr's checkpoints are pickles, and loading a pickle runs any code "
                       "its author put in it: add --trust-pickle only if you trust everyone who "
                       f"could write {args.dir}")
    was = imports_trusted()
    trust_imports()  # the folder is trusted: the code its configs name loads, for its checkpoints
    try:
        for run_ in run_dirs(args.dir):
            written = convert_task(run_) + convert_run(run_)
            if written:
                print(f"{run_.path}: {', '.join(written)}")
    finally:
        trust_imports(was)
    return 0
