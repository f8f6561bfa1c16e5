"""A run's champion as a runnable robot: body + dense controller read back from champion.json."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evolve.controller import DenseController
from evolve.graph_controller import FORMAT as GRAPH_FORMAT
from evolve.graph_controller import GraphController
from evolve.rundir import RunDir


def load_champion(run_dir: str | Path) -> tuple[dict, np.ndarray, DenseController | GraphController]:
    champ = RunDir(run_dir).champion()
    c = champ["controller"]
    ctrl = GraphController.from_json(c) if c.get("format") == GRAPH_FORMAT else DenseController.from_json(c)
    return champ, np.asarray(champ["body"]), ctrl


def champion_gif(run_dir: str | Path, out: str | Path | None = None, *, width: int = 640,
                 height: int = 320, fps: float = 30.0) -> Path:
    """Render the champion's episode in its task (same episode length as its evaluation)."""
    from tasks.render_episode import render_episode
    from tsim.render import write_gif

    champ, body, ctrl = load_champion(run_dir)
    frames = render_episode(champ["task"], body, lambda t, obs: ctrl.act(obs), champ["episode_steps"],
                            width, height, indexed=True)
    return write_gif(frames, out or Path(run_dir) / "champion.gif", fps=fps)
