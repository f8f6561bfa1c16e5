"""Measurement records: the JSON a benchmark or study writes beside its printout, so that a figure
the docs quote (docs/records/*.json, checked by tests/test_docs_facts.py) says which machine, which
commit, when and by which command it was measured.

A record: {"name", "figures": {key: {"value": number or [numbers], "unit"}}, "machine", "commit",
"date", "command", ...}; `value` lists a range's ends (several runs) or one number."""

from __future__ import annotations

import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cpu_model() -> str:
    """The CPU's model name and how many CPUs this process may use (the machine a figure is of)."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return f"{model}, {cpus} CPUs"


def commit() -> str:
    """The commit of the code measured, `+dirty` when the tree has changes; "unknown" outside git."""
    try:
        head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short=12", "HEAD"],
                              capture_output=True, text=True, timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def command_line() -> str:
    """This process's command as a user would type it: `sgr ...` or `python bench/x.py ...`, after
    the SGR_* environment variables that change what is measured."""
    prog = Path(sys.argv[0])
    if prog.name == "sgr" or (prog.name == "__main__.py" and prog.parent.name == "cli"):
        head = ["sgr"]
    else:
        try:
            head = ["python", prog.resolve().relative_to(ROOT).as_posix()]
        except ValueError:
            head = ["python", prog.name]
    env = [f"{k}={v}" for k, v in sorted(os.environ.items()) if k.startswith("SGR_")]
    return shlex.join([*env, *head, *sys.argv[1:]])


def figure(value: float | list[float], unit: str) -> dict:
    """One figure of a record (a list: a range's ends, or one value per case)."""
    return {"value": value, "unit": unit}


def make_record(name: str, figures: dict[str, dict], command: str | None = None, **extra) -> dict:
    """A record of `figures` measured now, here, by `command` (default: this process's command line)."""
    return {"name": name, "figures": figures, "machine": cpu_model(), "commit": commit(),
            "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%MZ"),
            "command": command or command_line(),
            "python": platform.python_version(), **extra}


def write_record(path: str | Path, name: str | None, figures: dict[str, dict], command: str | None = None,
                 **extra) -> dict:
    """Write a record to `path` (its name: the file's stem unless given) and return it."""
    path = Path(path)
    record = make_record(name or path.stem, figures, command, **extra)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=1) + "\n")
    return record
