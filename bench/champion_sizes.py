"""Bytes of the champion files a run writes (issue 36): a tiny Walker-v0 run of SGR and of direct
NEAT (2 generations of 8, 20-step episodes, seed 3) at 5x5, and the SGR champion's genome decoded
at 10x10 (`sgr decode`). Seconds on 2 cores.

    python bench/champion_sizes.py /tmp/champion-sizes     # a new folder
"""

from __future__ import annotations

import sys
from pathlib import Path

from evolve.records.decode import write_decoded
from evolve.runs.experiment import Experiment

TINY = {"task": "Walker-v0", "generations": 2, "pop_size": 8, "seed": 3, "episode_steps": 20, "workers": 1,
        "render_champion": False, "robust": None, "final_selection": None}


def main(out: Path) -> None:
    """Run both methods under `out` and print each champion.json's size."""
    for method in ("sgr", "direct"):
        with Experiment.from_config({"method": method, **TINY}, out / method, quiet=True) as exp:
            exp.run_all()
        print(f"{method} 5x5 champion.json: {(out / method / 'champion.json').stat().st_size} bytes")
    big = write_decoded(out / "sgr", (10, 10), out / "sgr-10x10")
    print(f"sgr 10x10 decoded champion.json: {(big / 'champion.json').stat().st_size} bytes")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
