"""champion.json, the file a run leaves for its champion: how it is written (`champion_record`,
`best_ever_record`) and read back, checked to run (`read_champion`). The champion as a runnable
robot, its replays and GIFs: evolve/records/replay.py.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evolve.config import MAX_EPISODE_STEPS
from evolve.methods.formats import controller_of
from evolve.nn.dense import DenseController
from evolve.nn.genome_record import record_size_problem
from evolve.nn.graph import GraphController
from evolve.records.elites import elite_record
from evolve.records.rundir import ELITES_FILE, RunDir, check_fitness
from tasks.env import obs_dim
from tasks.specs import MAX_SIDE, TASKS
from tsim.backend import DEFAULT_PRECISION, runtime
from tsim.body import build_body, check_robot
from tsim.errors import SgrError

KEYS = ("task", "episode_steps", "body", "controller")


def champion_record(cfg: dict, problem, genome, phenotype, fitness: float, generation: int,
                    evaluation: dict) -> dict:
    """champion.json's record of `genome` (decoded to `phenotype`) scored `fitness` as `evaluation`
    says (robust settings, seed, tag), found in `generation` (counted from 1); `problem` is the run's
    method (`Problem.champion` gives the body and controller)."""
    champ = {"format": "sgr-champion-1", "method": cfg.method, "task": cfg.task,
             "episode_steps": cfg.episode_steps, "fitness": fitness, "generation": generation,
             "precision": cfg.precision, "genome": problem.genome_record(genome)}
    method_keys = problem.champion_of(genome, phenotype)
    evaluation = {**evaluation, **method_keys.pop("evaluation", {})}
    champ.update(method_keys, evaluation=evaluation)
    return champ


def best_ever_record(cfg: dict, problem, best: dict) -> dict:
    """champion.json's record of a search's best-ever genome (`NeatSearch.best`), with how its
    fitness was scored: enough to score it again exactly (robust: the run's seed and the
    evaluation's tag give every episode's noise; the tag holds the search's own generation
    number, counted from 0)."""
    evaluation = {"robust": cfg.robust and cfg.robust.to_json(), "seed": cfg.seed}
    if "tags" in best:  # accumulated fitness: the mean of these evaluations' scores, in this order
        evaluation["tags"] = list(best["tags"])
    else:
        evaluation["tag"] = f"{best['generation']}/{best['key']}"
    champ = champion_record(cfg, problem, best["genome"], best["phenotype"], best["fitness"],
                            best["generation"] + 1, evaluation)
    champ.update(archive_place(best))
    return champ


def archive_place(entry: dict | None) -> dict:
    """champion.json's `archive` key for an elite of a map-elites archive (`MapElitesSearch.elite_entry`):
    its cell, its descriptors and, when the run recorded behaviour, its behaviour features; {} for
    anything else."""
    if not entry or "cell" not in entry:
        return {}
    place = {"cell": list(entry["cell"]), "measures": dict(entry["measures"])}
    if "behaviour" in entry:
        place["behaviour"] = dict(entry["behaviour"])
    return {"archive": place}


def read_champion(run_dir: str | Path,
                  cell=None) -> tuple[dict, np.ndarray, DenseController | GraphController]:
    """champion.json's record, body and controller (`load_champion` wraps them in a `Champion`);
    ValueError naming the file and the key when it is not a champion that runs (checked with one
    forward pass of the controller). `cell` (a map-elites run's; (i, j) or "i,j"): the record of
    that cell's elite in elites.json instead."""
    if Path(run_dir).is_file():  # champion.json itself: its run's other files are beside it
        raise SgrError(f"{run_dir} is a file: give its run's folder ({Path(run_dir).parent})")
    f = Path(run_dir) / ("champion.json" if cell is None else ELITES_FILE)
    if (Path(run_dir) / "config.yaml").is_file():  # a task of the user's: its imports, or a script's
        from evolve.records.run_config import read_run_config

        read_run_config(RunDir(run_dir))  # its task registered, every value of config.yaml checked
    champ = RunDir(run_dir).champion() if cell is None else elite_record(run_dir, cell)  # SgrError: not JSON
    return check_record(champ, f)


def check_record(champ: object, f: Path) -> tuple[dict, np.ndarray, DenseController | GraphController]:
    """A champion record (champion.json's, or one elite's of elites.json, as read from file `f`),
    its body and its controller, checked as `read_champion` says; SgrError naming `f` and the key."""
    if not isinstance(champ, dict):
        raise SgrError(f"{f}: a champion must be a JSON object with keys {', '.join(KEYS)}")
    missing = [k for k in KEYS if k not in champ]
    if missing:
        raise SgrError(f"{f}: missing key{'s' if len(missing) > 1 else ''} {', '.join(missing)}")
    if not isinstance(champ["task"], str) or champ["task"] not in TASKS:
        raise SgrError(f"{f}: key 'task': unknown task {champ['task']!r}")
    check_fitness(champ.get("fitness", 0.0), f)  # a hand-made record may leave it out
    if not isinstance(champ.get("evaluation", {}), dict | None):
        raise SgrError(f"{f}: key 'evaluation' must be a mapping (robust, seed, tag), got "
                       f"{str(champ['evaluation'])[:40]!r}")
    steps = champ["episode_steps"]
    positive = isinstance(steps, int) and not isinstance(steps, bool) and steps > 0
    if not (positive or steps in (None, "evogym")):
        raise SgrError(f"{f}: key 'episode_steps' must be a positive int, 'evogym' or null, got {steps!r}")
    if positive and steps > MAX_EPISODE_STEPS:
        raise SgrError(f"{f}: key 'episode_steps' must be at most {MAX_EPISODE_STEPS:,}, got {steps:,}")
    rows = champ["body"]
    if isinstance(rows, list) and (len(rows) > MAX_SIDE or any(isinstance(r, list) and len(r) > MAX_SIDE
                                                               for r in rows)):
        raise SgrError(f"{f}: key 'body': sgr places bodies of up to {MAX_SIDE}x{MAX_SIDE}")
    try:
        body = check_robot(champ["body"])
    except ValueError as exc:
        raise SgrError(f"{f}: key 'body': {exc}") from None
    b = build_body(body)
    if (why := record_size_problem(champ.get("genome"))) is not None:  # before anything compiles it
        raise SgrError(f"{f}: key 'genome': {why}")
    try:
        ctrl = controller_of(champ)
        actions = ctrl.act(np.zeros(obs_dim(champ["task"], b.n_points)))
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise SgrError(f"{f}: key 'controller': not a controller of this body and task "
                       f"({type(exc).__name__}: {exc})") from None
    if np.shape(actions) != (len(b.actuator_flat),):
        raise SgrError(f"{f}: key 'controller': gives {np.size(actions)} actions, the body has "
                       f"{len(b.actuator_flat)} actuators")
    # its fitness is reproducible in the precision it was scored in (records without the key: f64):
    # its replays pass that precision down to the simulator they build (`precision_of`); reading
    # the file only checks that this process can (it sets nothing: the file is data)
    precision = precision_of(champ)
    if precision not in runtime.PRECISIONS:
        raise SgrError(f"{f}: key 'precision': unknown precision {precision!r}; use one of "
                       f"{', '.join(runtime.PRECISIONS)}")
    if (why := runtime.switch_problem(precision)) is not None:
        raise SgrError(f"{f}: key 'precision': scored in {precision}, to be replayed in it: {why} "
                       "(start a new process)")
    return champ, body, ctrl


def precision_of(champ: dict) -> str:
    """The real type a champion record was scored in, which its replays simulate in (f64 for a
    record from before the key)."""
    return champ.get("precision") or DEFAULT_PRECISION


def episode_steps(task: str, steps: int | str | None) -> int:
    """The episode length a record stands for: runs record theirs; older ones wrote null (the
    paper's length for the task) or "evogym" (evogym's)."""
    return TASKS[task].episode_length(steps if steps is None or steps == "evogym" else int(steps))
