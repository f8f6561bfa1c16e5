"""A run's champion as a runnable robot (body + controller read back from champion.json by
evolve/records/champion.py), its replays and its GIFs.

    from evolve import load_champion
    champ = load_champion("runs/sgr-quick-seed0-...")      # body, policy, episode length, fitness
    champ.rollout() == champ.fitness                       # True: its episode, in gymnasium (*)
    env = champ.env()                                      # gymnasium env of its task and body
    champ.gif("champion.gif")

(*) for a run scored by one exact episode; with robust evaluation `rescore_champion` reproduces the
fitness.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evolve.nn.dense import DenseController
from evolve.nn.graph import GraphController
from evolve.records import verdict as verdict_rule
from evolve.records.champion import episode_steps, precision_of, read_champion
from evolve.records.elites import parse_cell
from evolve.rollout.episodes import rollout_policy
from evolve.rollout.robust import MAX_EPISODES, NOISE_KINDS, EpisodeNoise, Perturbation, Robust, episode_keys
from tasks.behaviour import FEATURES
from tasks.env import obs_dim
from tsim.body import build_body
from tsim.errors import SgrError

MEDIAN = "median"  # champion_gif's default replay: the verdict's typical perturbed episode


def champion_gif(run_dir: str | Path, out: str | Path | None = None, *, width: int = 640,
                 height: int = 320, fps: float = 30.0, replay: int | str = MEDIAN,
                 eps: float = verdict_rule.EPS, kind: str = "uniform", offset: float = 0.0, seed: int = 0,
                 every: int = 1, cell=None, overlay: bool = True) -> Path:
    """Render one of the champion's episodes in its task (same episode length as its evaluation; a
    frame every `every` steps): by default ("median") its typical perturbed episode, the replay
    whose return is the median of the verdict's `verdict.REPLAYS` replays under `kind` noise of
    scale `eps` (`typical_replay`); `replay` 0 its exact episode; `replay` I > 0 that perturbed
    replay of `replay_champion` (same arguments, same episode). Why the median: the exact episode is
    one draw of a chaotic system, which may be far from what the robot usually does. Default `out`:
    the run's champion.gif for the median, else its own file (`replay_gif_name`); champion.gif gets an
    MP4 of the same frames beside it where imageio's ffmpeg plugin is installed (champion.mp4), and an
    `out` ending in .mp4 is an MP4. `cell` (a map-elites run's, (i, j) or "i,j"): that cell's elite
    instead (elites.json), default `out` RUN/elite-I-J.gif (`elite_gif_name`). `overlay`: each frame
    says the task, the step and the return so far (False: the robot alone)."""
    from tasks.render_episode import render_episode
    from tsim.render import write_animation

    champ, body, ctrl = read_champion(run_dir, cell)
    index = (typical_replay(run_dir, eps, kind, offset, seed, cell=cell)[0] if replay == MEDIAN
             else int(replay))
    noise = _replay_noise(index, eps, kind, offset, seed).take([index])
    mp4_beside = out is None and replay == MEDIAN and cell is None
    out = out or Path(run_dir) / (replay_gif_name(replay) if cell is None else elite_gif_name(cell, replay))
    shift = noise.shifts()

    def policy(t: int, obs: np.ndarray) -> np.ndarray:
        a = ctrl.act(obs)
        extra = noise.actions(t, len(a))
        return a if extra is None else a + extra[0]

    steps = episode_steps(champ["task"], champ["episode_steps"])

    def line(t: int, total: float) -> str:
        return f"{champ['task']}   step {t} of {steps}   return {total:.3f}"

    frames = render_episode(champ["task"], body, policy, champ["episode_steps"], width, height,
                            every=every, indexed=True, start_shift=0.0 if shift is None else float(shift[0]),
                            precision=precision_of(champ), caption=line if overlay else None)
    return write_animation(frames, out, fps=fps, mp4_beside=mp4_beside)


def typical_replay(run_dir: str | Path, eps: float = verdict_rule.EPS, kind: str = "uniform",
                   offset: float = 0.0, seed: int = 0,
                   replays: int = verdict_rule.REPLAYS, cell=None) -> tuple[int, np.ndarray]:
    """The replay (1 to `replays`) whose return is the median of the champion's perturbed replays
    (`verdict.median_replay`; with the defaults, the verdict's replays), and all the returns
    (element 0 the exact episode). `cell`: a map-elites run's elite instead."""
    returns = replay_champion(run_dir, replays, eps, seed, kind, offset, cell)
    return verdict_rule.median_replay(returns), returns


def replay_gif_name(replay: int | str) -> str:
    """The GIF of a run's champion: champion.gif for its typical (median) replay, champion-exact.gif
    for its exact episode (replay 0), champion-replayI.gif for its perturbed replay I."""
    if replay == MEDIAN:
        return "champion.gif"
    return "champion-exact.gif" if replay == 0 else f"champion-replay{replay}.gif"


def elite_gif_name(cell, replay: int | str = MEDIAN) -> str:
    """The GIF of a map-elites run's elite of `cell`: elite-I-J.gif (its typical replay),
    elite-I-J-exact.gif, elite-I-J-replayK.gif."""
    cell = parse_cell(cell) if isinstance(cell, str) else tuple(int(i) for i in cell)
    name = "elite-" + "-".join(map(str, cell))
    if replay == MEDIAN:
        return f"{name}.gif"
    return f"{name}-exact.gif" if replay == 0 else f"{name}-replay{replay}.gif"


def replay_line(run_dir: str | Path, replay: int | str = MEDIAN, eps: float = verdict_rule.EPS,
                kind: str = "uniform", offset: float = 0.0, seed: int = 0, cell=None) -> str:
    """What `sgr render` prints beside the GIF: the champion's nominal return and, for a perturbed
    replay, that replay's return (the episode the GIF shows), to answer "does it hold?"; for the
    median, which replay it is and what the replays return."""
    noise = f"±{eps:g} {kind} action noise" + (f", start ±{offset:g}" if offset else "")
    if replay == MEDIAN:
        index, returns = typical_replay(run_dir, eps, kind, offset, seed, cell=cell)
        noisy = returns[1:]
        return (f"the median of {len(noisy)} replays ({noise}), replay {index}: return "
                f"{returns[index]:.4f} (replays {noisy.min():.4f} to {noisy.max():.4f}), nominal "
                f"return {returns[0]:.4f}; the exact episode: --exact")
    returns = replay_champion(run_dir, replay, eps, seed, kind, offset, cell)
    nominal = f"nominal return {returns[0]:.4f}"
    if replay == 0:
        return f"the exact episode: {nominal}"
    return f"replay {replay} ({noise}) return {returns[replay]:.4f}, {nominal}"


class _EachController:
    """A batched policy of one controller per world (each world its own body, or one body in all)."""

    def __init__(self, ctrls: list, n_obs: list[int], n_act: int):
        self.ctrls, self.n_obs, self.n_act = ctrls, n_obs, n_act

    def act(self, obs: np.ndarray) -> np.ndarray:
        """One forward pass per world, actions padded to the batch's widest body."""
        out = np.zeros((len(obs), self.n_act))
        for i, (c, n) in enumerate(zip(self.ctrls, self.n_obs, strict=True)):
            a = c.act(obs[i, :n])
            out[i, :len(a)] = a
        return out


def record_elite_nominals(run_dir: str | Path) -> int:
    """Write into a map-elites run's elites.json each elite's `nominal`, the return of its exact,
    noise-free episode (what `load_champion(run, cell=...).rollout()` gives), for the elites that
    lack it, all simulated as one batch per precision; returns how many were added. Why: an elite's
    fitness is a score under the run's noise, and its exact return is the other half of its
    verdict."""
    from evolve.records.champion import check_record
    from evolve.records.elites import read_elites
    from evolve.records.files import atomic_write, record_json
    from evolve.records.rundir import ELITES_FILE

    f = Path(run_dir) / ELITES_FILE
    data = read_elites(run_dir)
    todo = [e for e in data["elites"] if not isinstance(e["champion"].get("nominal"), int | float)]
    batches: dict[tuple, list] = {}  # one batch per (precision, task, episode length)
    for e in todo:
        champ, body, ctrl = check_record(e["champion"], f)
        batches.setdefault((precision_of(champ), champ["task"], champ["episode_steps"]), []).append(
            (e, body, ctrl))
    for (precision, task, steps), items in batches.items():
        bodies = [b for _, b, _ in items]
        n_obs = [obs_dim(task, build_body(b).n_points) for b in bodies]
        returns = rollout_policy(task, bodies, lambda env, items=items, n_obs=n_obs: _EachController(
            [c for *_, c in items], n_obs, env.sim.max_actuators), steps, precision=precision)
        for (e, *_), r in zip(items, returns, strict=True):
            e["champion"]["nominal"] = float(r)
    if todo:
        atomic_write(f, record_json(data).encode(), inside=Path(run_dir))
    return len(todo)


def _exact() -> EpisodeNoise:
    """The noise of one exact, unperturbed episode."""
    return EpisodeNoise(Perturbation(), np.zeros(1, np.uint64), np.zeros(1, bool))


def _replay(champ: dict, body: np.ndarray, ctrl, noise: EpisodeNoise, record: bool = False) -> np.ndarray:
    """Returns of len(noise.keys) episodes of the champion, each perturbed by its row of `noise`,
    as one batch through evolution's own episode loop (`record`: with their behaviour features,
    `rollout_policy`)."""
    n = len(noise.keys)
    n_obs = obs_dim(champ["task"], build_body(body).n_points)
    return rollout_policy(champ["task"], [body] * n,
                          lambda env: _EachController([ctrl] * n, [n_obs] * n, env.sim.max_actuators),
                          champ["episode_steps"], noise, precision=precision_of(champ), record=record)


def _scored_episodes(run_dir: str | Path, champ: dict) -> tuple[Robust | None, list[str], EpisodeNoise]:
    """How the champion's fitness was scored: its robust evaluation (None: one exact episode), the
    tags of its evaluations, and the perturbations of their episodes."""
    evaluation = champ.get("evaluation") or {}
    robust = Robust.from_config(evaluation.get("robust"), f"{Path(run_dir) / 'champion.json'}: evaluation")
    if robust is None:
        return None, [], _exact()
    tags = list(evaluation["tags"]) if "tags" in evaluation else [evaluation["tag"]]
    return robust, tags, robust.noise(evaluation["seed"], tags)


def champion_behaviour(run_dir: str | Path, cell=None) -> dict[str, float]:
    """What the champion does: its behaviour features (tasks/behaviour.py), the mean over the
    episodes its fitness scores (for a run scored by one exact episode, that episode), simulated
    from champion.json alone. `cell`: a map-elites run's elite of that cell instead."""
    champ, body, ctrl = read_champion(run_dir, cell)
    rows = _replay(champ, body, ctrl, _scored_episodes(run_dir, champ)[2], record=True)
    return dict(zip(FEATURES, rows[:, 1:].mean(axis=0).tolist(), strict=True))


def rescore_champion(run_dir: str | Path, cell=None) -> float:
    """The champion's fitness scored again from champion.json alone, as evolution scored it: its
    episode return, or for a run with robust evaluation the statistic over the same K perturbed
    episodes (the run's seed and the evaluation's tag give their noise). Must equal the recorded
    fitness. `cell`: a map-elites run's elite of that cell (elites.json) instead."""
    champ, body, ctrl = read_champion(run_dir, cell)
    robust, tags, noise = _scored_episodes(run_dir, champ)
    returns = _replay(champ, body, ctrl, noise)
    if robust is None:
        return float(returns[0])
    if "tags" not in champ["evaluation"]:
        return float(robust.score(returns[:, None])[0])
    # accumulated: each evaluation's score, summed in order, then the mean
    scores = robust.score(returns.reshape(robust.episodes, len(tags)))
    total = 0.0
    for s in scores:
        total += float(s)
    return total / len(tags)


def replay_champion(run_dir: str | Path, replays: int = 0, eps: float = 0.0, seed: int = 0,
                    kind: str = "uniform", offset: float = 0.0, cell=None) -> np.ndarray:
    """Episode returns of champion.json's robot in its task, from the JSON alone: element 0
    unperturbed (for a nominal run it must equal the recorded fitness), then `replays` episodes
    with `kind` noise of scale `eps` (uniform: +-eps; gaussian: sd eps) added to every action and
    the start shifted by uniform(+-offset), all simulated as one batch. Replay i's noise is a pure
    function of (seed, eps, kind, offset, i) (`evolve/rollout/robust.py`). `cell`: a map-elites
    run's elite of that cell instead (elites.json)."""
    champ, body, ctrl = read_champion(run_dir, cell)
    # every world replays evolution's episode (`rollout_policy`: seed 0, the constructed env's
    # episode), so the perturbed runs differ from it by the perturbation alone
    return _replay(champ, body, ctrl, _replay_noise(replays, eps, kind, offset, seed))


def headline(run_dir: str | Path, cell=None) -> verdict_rule.Verdict:
    """The champion's one figure (evolve/records/verdict.py, "One headline per champion"),
    simulated from champion.json alone: for a champion chosen by final selection, its held-out
    episodes again (the episodes of its `fitness`, whose mean this equals when the run's statistic
    is the mean) beside its exact episode; otherwise `verdict.REPLAYS` replays under the run's noise
    (uniform ±`verdict.EPS` for a nominal run) beside its exact episode. `cell`: a map-elites
    run's elite of that cell instead."""
    champ, body, ctrl = read_champion(run_dir, cell)
    evaluation = champ.get("evaluation") or {}
    robust = Robust.from_config(evaluation.get("robust"), f"{Path(run_dir) / 'champion.json'}: evaluation")
    exact = _exact()
    if robust is not None and str(evaluation.get("tag", "")).startswith("final-holdout/") \
            and "tags" not in evaluation:
        held = robust.noise(evaluation["seed"], [evaluation["tag"]])
        noise = EpisodeNoise(held.perturbation, np.concatenate([exact.keys, held.keys]),
                             np.concatenate([exact.on, held.on]))
        returns = _replay(champ, body, ctrl, noise)
        return verdict_rule.from_returns(returns, robust.action_scale, robust.action_noise, robust.offset,
                                         verdict_rule.HELD_OUT)
    if robust is None:
        kind, eps, offset = "uniform", verdict_rule.EPS, 0.0
    else:
        kind, eps, offset = robust.action_noise, robust.action_scale, robust.offset
    returns = _replay(champ, body, ctrl, _replay_noise(verdict_rule.REPLAYS, eps, kind, offset, 0))
    return verdict_rule.from_returns(returns, eps, kind, offset)


def record_headline(run) -> dict:
    """champion.json of `run` (a RunDir) with its `headline` (`headline`: the held-out mean return,
    its sd and the verdict), simulated from the file and written into it; the record as it is when
    it already has one, or when sgr cannot replay it (a registered method's own controller format:
    `load_champion` cannot either). Returns the record."""
    champ = run.champion()
    if verdict_rule.from_headline(champ.get("headline")) is None:
        try:
            champ["headline"] = headline(run.path).to_headline()
        except SgrError:  # a method of the user's whose controller sgr cannot replay: no headline
            return champ
        run.write_champion(champ)
    return champ


def judge(run_dir: str | Path, replays: int = verdict_rule.REPLAYS,
          eps: float = verdict_rule.EPS) -> verdict_rule.Verdict:
    """The verdict (evolve/records/verdict.py) on a run folder's champion.json: its robot replayed
    from the JSON alone, `replays` times under uniform(+-eps) and once without noise."""
    return load_champion(run_dir).verdict(replays, eps)


def _replay_noise(replays: int, eps: float, kind: str, offset: float, seed: int) -> EpisodeNoise:
    """The perturbations of replays 0 (none) to `replays`."""
    if (isinstance(replays, bool) or not isinstance(replays, numbers.Integral)
            or not 0 <= replays <= MAX_EPISODES):
        raise SgrError(f"replays must be an integer from 0 to {MAX_EPISODES:,}, got {replays!r}")
    n = int(replays) + 1
    if kind not in NOISE_KINDS:
        raise SgrError(f"noise kind must be one of {', '.join(NOISE_KINDS)}, got {kind!r}")
    real = all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in (eps, offset))
    if not (real and math.isfinite(eps) and math.isfinite(offset) and eps >= 0 and offset >= 0):
        raise SgrError(f"noise scale and start offset must be finite numbers >= 0, got {eps!r} and "
                       f"{offset!r}")
    tags = [f"replay/{kind}/{eps!r}/{offset!r}/{i}" for i in range(n)]
    return EpisodeNoise(Perturbation(kind, eps, offset), episode_keys(seed, tags, 0), np.arange(n) > 0)


@dataclass(frozen=True)
class Champion:
    """A run's champion, ready to use: its task, body and controller, episode length and fitness.

    `policy(obs) -> action` whatever the controller's format. `load_champion` reads one from a run.

    Attributes:
        task: Its task's id ("Walker-v0").
        body: Its body, the matrix of voxel materials.
        controller: Its controller, dense or graph.
        episode_steps: The episode length of its evaluation.
        fitness: The fitness of its evaluation.
        record: champion.json as read.
        cell: A map-elites run's elite: its cell of the archive; None for a run's champion.
    """

    task: str
    body: np.ndarray
    controller: DenseController | GraphController
    episode_steps: int
    fitness: float
    record: dict = field(repr=False)  # champion.json as read
    cell: tuple[int, ...] | None = None  # a map-elites run's elite: its cell of the archive

    @property
    def nominal(self) -> float | None:
        """The return of its exact, noise-free episode as evolution computed it (`rollout()` again).

        For a run scored by that episode, its fitness. For a champion chosen by final selection
        (whose fitness is its score under noise), the recorded nominal return. For a champion
        scored under noise alone, its headline's exact episode, or a map-elites elite's recorded
        `nominal` (`record_elite_nominals`). None for a record without them (`verdict()` replays
        it).
        """
        if (self.record.get("evaluation") or {}).get("robust") is None:
            return self.fitness
        selection = self.record.get("selection")
        if selection is not None:
            return float(selection["nominal"])
        if isinstance(self.record.get("nominal"), int | float):  # a map-elites elite's, recorded at the end
            return float(self.record["nominal"])
        h = self.headline
        return None if h is None else h.nominal

    @property
    def headline(self) -> verdict_rule.Verdict | None:
        """Its one figure as its run recorded it: champion.json's `headline`.

        The headline is the mean return of held-out episodes under the run's noise, their sd, and
        the verdict (evolve/records/verdict.py). None for a record written before headlines
        (`headline(run_dir)` simulates it).
        """
        return verdict_rule.from_headline(self.record.get("headline"))

    def __repr__(self) -> str:
        from tsim.body import describe_body

        h = self.headline
        if h is not None:  # the headline, as the console and the report show it
            figure = (f"return={h.noisy_mean:.4g}±{h.sd:.2g} over {h.replays} {h.episodes} "
                      f"({h.noise}), {h.label}, exact={h.nominal:.4g}")
        else:
            nominal = self.nominal
            figure = (f"fitness={self.fitness:.6g}"
                      + ("" if nominal is None else f", nominal={nominal:.6g}"))
        return (f"Champion(task={self.task!r}, {describe_body(self.body)}, {self.controller!r}, "
                f"episode_steps={self.episode_steps}, {figure}"
                + (f", cell={self.cell}" if self.cell is not None else "") + ")")

    def policy(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n_actuators,) for one observation, computed as in evolution (bit for bit)."""
        return self.controller.act(obs)

    @property
    def precision(self) -> str:
        """The real type its fitness was scored in: its env and replays simulate in it."""
        return precision_of(self.record)

    def env(self, **kwargs):
        """A gymnasium env of its task and body, with its episode length and its precision.

        That is `gymnasium.make("sgr/<task>", body=..., max_episode_steps=<its episode length>,
        precision=<its precision>)`; `kwargs` go to gymnasium.make.
        """
        import gymnasium as gym

        import tasks  # noqa: F401  (registers the sgr/<task> ids)

        return gym.make(f"sgr/{self.task}", body=self.body,
                        **{"max_episode_steps": self.episode_steps, "precision": self.precision, **kwargs})

    def rollout(self, env=None) -> float:
        """The return of its episode in gymnasium, reset with seed 0 as evolution's episode was.

        So it equals `nominal` exactly (and `fitness`, for a run scored by one exact episode). A run
        with robust evaluation scored a statistic over perturbed episodes: `rescore_champion(run_dir)`
        reproduces that.

        Args:
            env (gymnasium.Env | None): The env to run it in; None: `env()`.

        Returns:
            The episode's return.
        """
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
        """Whether it holds: its episode replayed under action noise, against its noise-free return.

        The rule is evolve/records/verdict.py's. `verdict().line()` says it in words;
        `verdict().holds` is the rule's answer.

        Args:
            replays: How many times its episode is replayed.
            eps: The noise on every action: uniform(+-eps).
        """
        returns = _replay(self.record, self.body, self.controller,
                          _replay_noise(replays, eps, "uniform", 0.0, 0))
        return verdict_rule.from_returns(returns, eps)

    def gif(self, out: str | Path, *, width: int = 640, height: int = 320, fps: float = 30.0) -> Path:
        """Render its episode to a GIF at `out`; returns the path."""
        from tasks.render_episode import render_episode
        from tsim.render import write_gif

        frames = render_episode(self.task, self.body, lambda t, obs: self.policy(obs), self.episode_steps,
                                width, height, indexed=True, precision=self.precision)
        return write_gif(frames, out, fps=fps)


def load_champion(run_dir: str | Path, cell=None) -> Champion:
    """The champion of a run directory (its champion.json), checked to run.

    Args:
        run_dir: The run's folder.
        cell (tuple[int, int] | str | None): A map-elites run's cell of its archive, (i, j) or
            "i,j": that cell's elite (elites.json) instead.

    Returns:
        The champion, ready to use.

    Raises:
        ValueError: It does not run; the message names the file and the key.
    """
    record, body, ctrl = read_champion(run_dir, cell)
    if cell is not None:
        cell = parse_cell(cell) if isinstance(cell, str) else tuple(int(i) for i in np.asarray(cell).ravel())
    return Champion(task=record["task"], body=body, controller=ctrl,
                    episode_steps=episode_steps(record["task"], record["episode_steps"]),
                    fitness=float(record.get("fitness", float("nan"))), record=record, cell=cell)
