"""`sgr validate DIR`: evogym's recorded traces or returns replayed through sgr's tasks, and the
disagreement printed (parity.harness)."""

from __future__ import annotations

import argparse
import json

from tasks.cli import PRECISION_HELP, PRECISIONS


def register(sub) -> argparse.ArgumentParser:
    """Add `validate` to an argparse subparsers object."""
    v = sub.add_parser("validate", help="compare with evogym reference traces or returns")
    v.add_argument("dir", help="a folder of evogym reference data (index.json and its .npz files), "
                               "e.g. tests/data/traces or tests/data/evogym32")
    v.add_argument("--json", action="store_true", help="print the comparison as JSON")
    v.add_argument("--precision", choices=PRECISIONS, help=PRECISION_HELP)
    v.set_defaults(fn=run)
    return v


def run(args: argparse.Namespace) -> int:
    """Replay the folder `args.dir` and print each case's and each task's errors (or JSON)."""
    from parity.harness import validate  # (scipy and Taichi: only when the command runs)
    from tsim import backend
    from tsim.backend import runtime

    runtime.use_precision(args.precision)
    here = backend.get()  # one that cannot start fails here, in one line
    if not args.json:
        print(here.line(), flush=True)
    report = validate(args.dir)
    if args.json:
        print(json.dumps({**report, "backend": here.record()}))
        return 0
    for c in report["cases"]:
        print(f"{c['file']:<48} {c['task']:<22} com_err_final {c['com_err_final']:.2e} "
              f"com_err_max50 {c['com_err_max50']:.2e} obs_err_step0 {c['obs_err_step0']:.1e} "
              f"return_err {c['return_err']:.2e}")
    for task, t in report["tasks"].items():
        print(task, " ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                             for k, v in t.items()))
    return 0
