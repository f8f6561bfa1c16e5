"""The Python blocks of the README and docs/FIRST_HOUR.md run as written: each ```python block is
executed, in order, in one fresh process in an empty folder (`<time>` in a run folder's name,
which stands for the time a run was started, is that of a tiny run made there first). A block
that fails names itself."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

ROOT = Path(__file__).resolve().parents[1]

RUNNER = '''
import json, sys, traceback
blocks = json.loads(sys.argv[1])
from evolve import Experiment
exp = Experiment.from_config({"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 8,
                              "episode_steps": 250, "workers": 1, "robust": None, "final_selection": None},
                             "runs/sgr-quick-seed0-TEST", quiet=True)
exp.run_all(); exp.finish()
for i, code in enumerate(blocks):
    try:
        exec(compile(code, f"README.md python block {i + 1}", "exec"), {"__name__": "__readme__"})
    except Exception:
        traceback.print_exc()
        print(f"README.md python block {i + 1} failed:\\n{code}", file=sys.stderr)
        sys.exit(1)
print(f"ran {len(blocks)} blocks")
'''


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_readme_python_blocks_run_as_written(tmp_path):
    """The README's blocks, then docs/FIRST_HOUR.md's (the first hour in full)."""
    pages = [(ROOT / "README.md").read_text(), (ROOT / "docs" / "FIRST_HOUR.md").read_text()]
    blocks = [b.replace("<time>", "TEST") for page in pages for b in python_blocks(page)]
    assert len(blocks) >= 6  # use your champion (twice), the API, BatchEnv, gymnasium, coming from evogym
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    env["PYTHONPATH"] = str(ROOT)
    r = subprocess.run([sys.executable, "-c", RUNNER, json.dumps(blocks)], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-4000:]
    assert r.stdout.strip().endswith(f"ran {len(blocks)} blocks")
