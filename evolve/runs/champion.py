"""A run's champion as a runnable robot: body + controller read back from champion.json.

    from evolve import load_champion
    champ = load_champion("runs/sgr-quick-seed0-...")      # body, policy, episode length, fitness
    champ.rollout() == champ.fitness                       # True: its episode, in gymnasium (*)
    env = champ.env()                                      # gymnasium env of its task and body
    champ.gif("champion.gif")

(*) for a run scored by one exact episode; with robust evaluation `rescore_champion` reproduces the
fitness.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evolve.methods.formats import controller_of
from evolve.nn.dense import DenseController
from evolve.nn.graph import GraphController
from evolve.rollout.episodes import rollout_policy
from evolve.rollout.robust import NOISE_KINDS, EpisodeNoise, Perturbation, Robust, episode_keys
from evolve.runs import verdict as verdict_rule
from evolve.runs.rundir import RunDir
from evolve.search.genome_record import genome_json
from tasks.env import obs_dim
from tasks.specs import TASKS
from tsim import runtime
from tsim.backend import DEFAULT_PRECISION
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
             "precision": cfg.precision, "genome": genome_json(genome)}
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
    return champion_record(cfg, problem, best["genome"], best["phenotype"], best["fitness"],
                           best["generation"] + 1, evaluation)


def read_champion(run_dir: str | Path) -> tuple[dict, np.ndarray, DenseController | GraphController]:
    """champion.json's record, body and controller (`load_champion` wraps them in a `Champion`);
    ValueError naming the file and the key when it is not a champion that runs (checked with one
    forward pass of the controller)."""
    f = Path(run_dir) / "champion.json"
    if (Path(run_dir) / "config.yaml").is_file():  # a task of the user's: its imports, or a script's
        run = RunDir(run_dir)
        run.load_task(run.config())
    try:
        champ = RunDir(run_dir).champion()
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SgrError(f"{f}: not valid JSON ({exc})") from None
    if not isinstance(champ, dict):
        raise SgrError(f"{f}: a champion must be a JSON object with keys {', '.join(KEYS)}")
    missing = [k for k in KEYS if k not in champ]
    if missing:
        raise SgrError(f"{f}: missing key{'s' if len(missing) > 1 else ''} {', '.join(missing)}")
    if champ["task"] not in TASKS:
        raise SgrError(f"{f}: key 'task': unknown task {champ['task']!r}")
    steps = champ["episode_steps"]
    positive = isinstance(steps, int) and not isinstance(steps, bool) and steps > 0
    if not (positive or steps in (None, "evogym")):
        raise SgrError(f"{f}: key 'episode_steps' must be a positive int, 'evogym' or null, got {steps!r}")
    try:
        body = check_robot(champ["body"])
    except ValueError as exc:
        raise SgrError(f"{f}: key 'body': {exc}") from None
    b = build_body(body)
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


MEDIAN = "median"  # champion_gif's default replay: the verdict's typical perturbed episode


def champion_gif(run_dir: str | Path, out: str | Path | None = None, *, width: int = 640,
                 height: int = 320, fps: float = 30.0, replay: int | str = MEDIAN,
                 eps: float = verdict_rule.EPS, kind: str = "uniform", offset: float = 0.0, seed: int = 0,
                 every: int = 1) -> Path:
    """Render one of the champion's episodes in its task (same episode length as its evaluation; a
    frame every `every` steps): by default ("median") its typical perturbed episode, the replay
    whose return is the median of the verdict's `verdict.REPLAYS` replays under `kind` noise of
    scale `eps` (`typical_replay`); `replay` 0 its exact episode; `replay` I > 0 that perturbed
    replay of `replay_champion` (same arguments, same episode). Why the median: the exact episode is
    one draw of a chaotic system, which may be far from what the robot usually does. Default `out`:
    the run's champion.gif for the median, else its own file (`replay_gif_name`); champion.gif gets an
    MP4 of the same frames beside it where imageio's ffmpeg plugin is installed (champion.mp4), and an
    `out` ending in .mp4 is an MP4."""
    from tasks.render_episode import render_episode
    from tsim.render import write_animation

    champ, body, ctrl = read_champion(run_dir)
    index = typical_replay(run_dir, eps, kind, offset, seed)[0] if replay == MEDIAN else int(replay)
    noise = _replay_noise(index + 1, eps, kind, offset, seed).take([index])
    mp4_beside = out is None and replay == MEDIAN
    out = out or Path(run_dir) / replay_gif_name(replay)
    shift = noise.shifts()

    def policy(t: int, obs: np.ndarray) -> np.ndarray:
        a = ctrl.act(obs)
        extra = noise.actions(t, len(a))
        return a if extra is None else a + extra[0]

    frames = render_episode(champ["task"], body, policy, champ["episode_steps"], width, height,
                            every=every, indexed=True, start_shift=0.0 if shift is None else float(shift[0]),
                            precision=precision_of(champ))
    return write_animation(frames, out, fps=fps, mp4_beside=mp4_beside)


def typical_replay(run_dir: str | Path, eps: float = verdict_rule.EPS, kind: str = "uniform",
                   offset: float = 0.0, seed: int = 0,
                   replays: int = verdict_rule.REPLAYS) -> tuple[int, np.ndarray]:
    """The replay (1 to `replays`) whose return is the median of the champion's perturbed replays
    (`verdict.median_replay`; with the defaults, the verdict's replays), and all the returns
    (element 0 the exact episode)."""
    returns = replay_champion(run_dir, replays, eps, seed, kind, offset)
    return verdict_rule.median_replay(returns), returns


def replay_gif_name(replay: int | str) -> str:
    """The GIF of a run's champion: champion.gif for its typical (median) replay, champion-exact.gif
    for its exact episode (replay 0), champion-replayI.gif for its perturbed replay I."""
    if replay == MEDIAN:
        return "champion.gif"
    return "champion-exact.gif" if replay == 0 else f"champion-replay{replay}.gif"


def replay_line(run_dir: str | Path, replay: int | str = MEDIAN, eps: float = verdict_rule.EPS,
                kind: str = "uniform", offset: float = 0.0, seed: int = 0) -> str:
    """What `sgr render` prints beside the GIF: the champion's nominal return and, for a perturbed
    replay, that replay's return (the episode the GIF shows), to answer "does it hold?"; for the
    median, which replay it is and what the replays return."""
    noise = f"±{eps:g} {kind} action noise" + (f", start ±{offset:g}" if offset else "")
    if replay == MEDIAN:
        index, returns = typical_replay(run_dir, eps, kind, offset, seed)
        noisy = returns[1:]
        return (f"the median of {len(noisy)} replays ({noise}), replay {index}: return "
                f"{returns[index]:.4f} (replays {noisy.min():.4f} to {noisy.max():.4f}), nominal "
                f"return {returns[0]:.4f}; the exact episode: --exact")
    returns = replay_champion(run_dir, replay, eps, seed, kind, offset)
    nominal = f"nominal return {returns[0]:.4f}"
    if replay == 0:
        return f"the exact episode: {nominal}"
    return f"replay {replay} ({noise}) return {returns[replay]:.4f}, {nominal}"


class _SameController:
    """A batched policy of one controller driving every world (all worlds hold the same body)."""

    def __init__(self, ctrl: DenseController | GraphController, n_obs: int):
        self.ctrl, self.n_obs = ctrl, n_obs

    def act(self, obs: np.ndarray) -> np.ndarray:
        """One forward pass per world (a replay has few)."""
        return np.stack([self.ctrl.act(o[:self.n_obs]) for o in obs])


def _replay(champ: dict, body: np.ndarray, ctrl, noise: EpisodeNoise) -> np.ndarray:
    """Returns of len(noise.keys) episodes of the champion, each perturbed by its row of `noise`,
    as one batch through evolution's own episode loop."""
    n_obs = obs_dim(champ["task"], build_body(body).n_points)
    return rollout_policy(champ["task"], [body] * len(noise.keys), lambda env: _SameController(ctrl, n_obs),
                          champ["episode_steps"], noise, precision=precision_of(champ))


def rescore_champion(run_dir: str | Path) -> float:
    """The champion's fitness scored again from champion.json alone, as evolution scored it: its
    episode return, or for a run with robust evaluation the statistic over the same K perturbed
    episodes (the run's seed and the evaluation's tag give their noise). Must equal the recorded
    fitness."""
    champ, body, ctrl = read_champion(run_dir)
    evaluation = champ.get("evaluation") or {}
    robust = Robust.from_config(evaluation.get("robust"), f"{Path(run_dir) / 'champion.json'}: evaluation")
    if robust is None:
        return float(_replay(champ, body, ctrl, EpisodeNoise(Perturbation(), np.zeros(1, np.uint64),
                                                             np.zeros(1, bool)))[0])
    if "tags" not in evaluation:
        returns = _replay(champ, body, ctrl, robust.noise(evaluation["seed"], [evaluation["tag"]]))
        return float(robust.score(returns[:, None])[0])
    tags = evaluation["tags"]  # accumulated: each evaluation's score, summed in order, then the mean
    returns = _replay(champ, body, ctrl, robust.noise(evaluation["seed"], tags))
    scores = robust.score(returns.reshape(robust.episodes, len(tags)))
    total = 0.0
    for s in scores:
        total += float(s)
    return total / len(tags)


def replay_champion(run_dir: str | Path, replays: int = 0, eps: float = 0.0, seed: int = 0,
                    kind: str = "uniform", offset: float = 0.0) -> np.ndarray:
    """Episode returns of champion.json's robot in its task, from the JSON alone: element 0
    unperturbed (for a nominal run it must equal the recorded fitness), then `replays` episodes
    with `kind` noise of scale `eps` (uniform: +-eps; gaussian: sd eps) added to every action and
    the start shifted by uniform(+-offset), all simulated as one batch. Replay i's noise is a pure
    function of (seed, eps, kind, offset, i) (`evolve/rollout/robust.py`)."""
    champ, body, ctrl = read_champion(run_dir)
    # every world replays evolution's episode (`rollout_policy`: seed 0, the constructed env's
    # episode), so the perturbed runs differ from it by the perturbation alone
    return _replay(champ, body, ctrl, _replay_noise(replays + 1, eps, kind, offset, seed))


def judge(run_dir: str | Path, replays: int = verdict_rule.REPLAYS,
          eps: float = verdict_rule.EPS) -> verdict_rule.Verdict:
    """The verdict (evolve/runs/verdict.py) on a run folder's champion.json: its robot replayed
    from the JSON alone, `replays` times under uniform(+-eps) and once without noise."""
    return load_champion(run_dir).verdict(replays, eps)


def _replay_noise(n: int, eps: float, kind: str, offset: float, seed: int) -> EpisodeNoise:
    """The perturbations of replays 0 (none) to n - 1."""
    if kind not in NOISE_KINDS:
        raise SgrError(f"noise kind must be one of {', '.join(NOISE_KINDS)}, got {kind!r}")
    if not (eps >= 0 and offset >= 0):
        raise SgrError(f"noise scale and start offset must be >= 0, got {eps} and {offset}")
    tags = [f"replay/{kind}/{eps!r}/{offset!r}/{i}" for i in range(n)]
    return EpisodeNoise(Perturbation(kind, eps, offset), episode_keys(seed, tags, 0), np.arange(n) > 0)


def episode_steps(task: str, steps: int | str | None) -> int:
    """The episode length a record stands for: runs record theirs; older ones wrote null (the
    paper's length for the task) or "evogym" (evogym's)."""
    return TASKS[task].episode_length(steps if steps is None or steps == "evogym" else int(steps))


@dataclass(frozen=True)
class Champion:
    """A run's champion, ready to use: its task, body, controller and the episode length and
    fitness of its evaluation. `policy(obs) -> action` whatever the controller's format."""

    task: str
    body: np.ndarray
    controller: DenseController | GraphController
    episode_steps: int
    fitness: float
    record: dict = field(repr=False)  # champion.json as read

    @property
    def nominal(self) -> float | None:
        """The return of its exact, noise-free episode as evolution computed it (what `rollout()`
        gives again): its fitness for a run scored by that episode, the recorded nominal return
        for a champion chosen by final selection (whose fitness is its score under noise); None
        for a champion scored under noise alone (`verdict()` replays it)."""
        if (self.record.get("evaluation") or {}).get("robust") is None:
            return self.fitness
        selection = self.record.get("selection")
        return None if selection is None else float(selection["nominal"])

    def policy(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n_actuators,) for one observation, computed as in evolution (bit for bit)."""
        return self.controller.act(obs)

    @property
    def precision(self) -> str:
        """The real type its fitness was scored in: its env and replays simulate in it."""
        return precision_of(self.record)

    def env(self, **kwargs):
        """`gymnasium.make("sgr/<task>", body=..., max_episode_steps=<its episode length>,
        precision=<its precision>)`; `kwargs` go to gymnasium.make."""
        import gymnasium as gym

        import tasks  # noqa: F401  (registers the sgr/<task> ids)

        return gym.make(f"sgr/{self.task}", body=self.body,
                        **{"max_episode_steps": self.episode_steps, "precision": self.precision, **kwargs})

    def rollout(self, env=None) -> float:
        """The return of its episode in gymnasium (`env()`, or `env` given): reset with seed 0,
        as evolution's episode was, so it equals `nominal` exactly (and `fitness`, for a run scored
        by one exact episode). (A run with robust evaluation scored a statistic over perturbed
        episodes: `rescore_champion(run_dir)` reproduces that.)"""
        env = self.env() if env is None else env
        obs, _ = env.reset(seed=0)
        total, done = 0.0, False
        while not done:
            obs, reward, terminated, truncated, _ = env.step(self.policy(obs))
            total += reward
            done = terminated or truncated
        return total

    def verdict(self, replays: int = verdict_rule.REPLAYS,
                eps: float = verdict_rule.EPS) -> verdict_rule.Verdict:
        """Whether it holds (evolve/runs/verdict.py): its episode replayed `replays` times with
        uniform(+-eps) on every action, against its noise-free return. `verdict().line()` says it
        in words; `verdict().holds` is the rule's answer."""
        returns = _replay(self.record, self.body, self.controller,
                          _replay_noise(replays + 1, eps, "uniform", 0.0, 0))
        return verdict_rule.from_returns(returns, eps)

    def gif(self, out: str | Path, *, width: int = 640, height: int = 320, fps: float = 30.0) -> Path:
        """Render its episode to a GIF at `out`; returns the path."""
        from tasks.render_episode import render_episode
        from tsim.render import write_gif

        frames = render_episode(self.task, self.body, lambda t, obs: self.policy(obs), self.episode_steps,
                                width, height, indexed=True, precision=self.precision)
        return write_gif(frames, out, fps=fps)


def load_champion(run_dir: str | Path) -> Champion:
    """The champion of a run directory (its champion.json), checked to run: ValueError naming the
    file and the key otherwise."""
    record, body, ctrl = read_champion(run_dir)
    return Champion(task=record["task"], body=body, controller=ctrl,
                    episode_steps=episode_steps(record["task"], record["episode_steps"]),
                    fitness=float(record.get("fitness", float("nan"))), record=record)
