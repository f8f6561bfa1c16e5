"""PPO for many bodies at once: each body its own actor-critic, all trained in one batched simulation.

`train_bodies` trains one policy per body as stable-baselines3's PPO would train it alone on
`n_envs` copies of the body (evogym's `examples/ppo/run.py` loop), but every body's envs are
worlds of one `BatchEnv`, and every body's networks are slices of one stacked set of weights:
one forward pass per step drives the whole batch, one backward pass per minibatch updates every
body. What SB3 does, kept here: its `MlpPolicy` (separate policy and value MLPs of tanh layers, a
state-independent log std starting at 0, orthogonal initialisation with gains sqrt(2), 0.01 and
1), Adam with eps 1e-5, GAE, per-minibatch advantage normalisation, the clipped surrogate, the
value loss without clipping, gradient clipping by norm (per body here: each body is its own
optimisation), actions clipped to the action space when stepping, and the value of the final
observation added to the reward of a time-limit truncation. Randomness comes from one seeded
torch generator, and torch runs on one thread while training, so the same call gives the same
weights bit for bit (a resumed run trains as the uninterrupted one did).

Needs torch (the `[rl]` extra); the trained actors come back as numpy `MlpController`s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields

import numpy as np

from evolve.nn.mlp import ACTION_HIGH, ACTION_LOW, MlpController
from evolve.rollout.robust import check_mapping
from tasks.env import BatchEnv
from tsim.errors import SgrError

INSTALL_RL = "pip install 'sgr[rl]'"


def require_torch(what: str = "method 'ga-ppo'"):
    """torch, or SgrError in one line saying how to install it."""
    try:
        import torch
    except ImportError:
        raise SgrError(f"{what} trains with PPO and needs torch, which is not installed: "
                       f"{INSTALL_RL}") from None
    return torch


@dataclass(frozen=True)
class PpoSettings:
    """The `ppo` config key; defaults: evogym's PPO arguments (examples/ppo/args.py).

    Args:
        timesteps: environment steps per body (evogym's total_timesteps).
        n_envs: environments per body (copies of the body, each a world of the batch).
        n_steps: steps per environment between updates.
        batch_size: samples per minibatch (of n_steps x n_envs per body).
        n_epochs: passes over the samples per update.
        learning_rate, gamma, gae_lambda, clip_range, ent_coef, vf_coef, max_grad_norm: as SB3's PPO.
        hidden: the widths of the policy's and the value function's hidden layers.
    """
    timesteps: int = 1_000_000
    n_envs: int = 1
    n_steps: int = 128
    batch_size: int = 4
    n_epochs: int = 4
    learning_rate: float = 2.5e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.1
    ent_coef: float = 0.01
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: tuple[int, ...] = (64, 64)

    @classmethod
    def from_config(cls, raw: object, source: str = "config") -> PpoSettings:
        """The checked `ppo` mapping ({}: every default); SgrError naming the key otherwise."""
        keys = [f.name for f in fields(cls)]
        name = f"{source}: key 'ppo"
        check_mapping(raw, keys, name)
        values = {}
        for f in fields(cls):
            v = raw.get(f.name, f.default)
            if f.name == "hidden":
                v = tuple(v) if isinstance(v, list | tuple) else v
                if not (isinstance(v, tuple) and v and all(_is_int(h) and 1 <= h <= 4096 for h in v)):
                    raise SgrError(f"{name}.hidden' must be a list of layer widths from 1 to 4096, got {v!r}")
            elif isinstance(f.default, int):
                top = 10**10 if f.name == "timesteps" else 1 << 20
                if not (_is_int(v) and 1 <= v <= top):
                    raise SgrError(f"{name}.{f.name}' must be an int from 1 to {top:,}, got {v!r}")
            else:
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or v < 0:
                    raise SgrError(f"{name}.{f.name}' must be a number >= 0, got {v!r}")
                v = float(v)
                if f.name in ("gamma", "gae_lambda") and v > 1:
                    raise SgrError(f"{name}.{f.name}' must be at most 1, got {v!r}")
                if f.name in ("learning_rate", "clip_range", "max_grad_norm") and v == 0:
                    raise SgrError(f"{name}.{f.name}' must be > 0, got {v!r}")
            values[f.name] = v
        if values["batch_size"] > values["n_steps"] * values["n_envs"]:
            raise SgrError(f"{name}.batch_size' ({values['batch_size']}) must be at most n_steps x n_envs "
                           f"({values['n_steps'] * values['n_envs']}), the samples of one update")
        return cls(**values)

    def to_json(self) -> dict:
        """The settings as the config's mapping."""
        d = asdict(self)
        d["hidden"] = list(self.hidden)
        return d

    @property
    def updates(self) -> int:
        """Rollout-and-update rounds per body: SB3 runs until `timesteps` are reached or passed."""
        return -(-self.timesteps // (self.n_steps * self.n_envs))


def _is_int(v: object) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


@dataclass
class Trained:
    """What `train_bodies` returns for each body: its actor and how training went."""
    controller: MlpController
    timesteps: int
    episodes: int  # episodes finished while training
    mean_return: float  # the mean return of the last 10 of them (NaN: none finished)


class _Stack:
    """The actor-critics of B bodies, SB3's MlpPolicy shape, as stacked parameters: each layer's
    weights (B, in, out) and biases (B, 1, out), the log std (B, 1, actions)."""

    def __init__(self, torch, obs_dims: np.ndarray, n_actions: np.ndarray, width: int, actions: int,
                 hidden: tuple[int, ...], gen) -> None:
        self.torch = torch
        B = len(obs_dims)
        sizes = [width, *hidden]

        def mlp():
            return [self._layer(sizes[i], sizes[i + 1], math.sqrt(2), obs_dims if i == 0 else None, None,
                                gen, B) for i in range(len(hidden))]

        self.pi, self.vf = mlp(), mlp()
        self.mu = self._layer(hidden[-1], actions, 0.01, None, n_actions, gen, B)
        self.value = self._layer(hidden[-1], 1, 1.0, None, None, gen, B)
        self.log_std = torch.zeros((B, 1, actions), dtype=torch.float32, requires_grad=True)
        self.params = [p for layer in (*self.pi, *self.vf, self.mu, self.value) for p in layer]
        self.params.append(self.log_std)

    def _layer(self, n_in: int, n_out: int, gain: float, rows, cols, gen, B: int):
        """Weights (B, n_in, n_out), each body's real block orthogonal (as torch's orthogonal_ on a
        Linear's (out, in) weight) and its padding zero; biases (B, 1, n_out) zero."""
        torch = self.torch
        W = torch.zeros((B, n_in, n_out), dtype=torch.float32)
        for b in range(B):  # once, at initialisation
            r = int(rows[b]) if rows is not None else n_in
            c = int(cols[b]) if cols is not None else n_out
            block = torch.empty((c, r), dtype=torch.float32)
            torch.nn.init.orthogonal_(block, gain=gain, generator=gen)
            W[b, :r, :c] = block.T
        return [W.requires_grad_(True), torch.zeros((B, 1, n_out), dtype=torch.float32, requires_grad=True)]

    def forward(self, x):
        """(B, n, width) observations -> means (B, n, actions), values (B, n)."""
        torch = self.torch
        h, g = x, x
        for W, b in self.pi:
            h = torch.tanh(torch.baddbmm(b, h, W))
        for W, b in self.vf:
            g = torch.tanh(torch.baddbmm(b, g, W))
        mu = torch.baddbmm(self.mu[1], h, self.mu[0])
        return mu, torch.baddbmm(self.value[1], g, self.value[0])[..., 0]

    def clip_grads(self, max_norm: float) -> None:
        """Scale each body's gradient to at most `max_norm` (its own norm over all its parameters,
        as torch's clip_grad_norm_ does for one model)."""
        torch, B = self.torch, self.log_std.shape[0]
        grads = [p.grad for p in self.params]
        norm = torch.cat([g.reshape(B, -1) for g in grads], dim=1).norm(dim=1)
        coef = (max_norm / (norm + 1e-6)).clamp(max=1.0).view(B, 1, 1)
        for g in grads:
            g.mul_(coef)

    def actor(self, b: int, obs_dim: int, n_act: int) -> MlpController:
        """Body b's actor as a numpy controller (float32 weights, exactly, in float64)."""
        layers = [*self.pi, self.mu]
        ws = [W[b].detach().numpy().astype(np.float64) for W, _ in layers]
        bs = [bias[b, 0].detach().numpy().astype(np.float64) for _, bias in layers]
        ws[0] = ws[0][:obs_dim].copy()
        ws[-1], bs[-1] = ws[-1][:, :n_act].copy(), bs[-1][:n_act].copy()
        return MlpController(ws, bs, obs_dim, n_act)


def train_bodies(task: str, bodies: Sequence[np.ndarray], settings: PpoSettings, seed: int,
                 episode_steps: int | str | None = None, precision: str | None = None) -> list[Trained]:
    """Train one policy per body with PPO, every body's `n_envs` environments in one batch.

    Args:
        task: the task every body learns.
        bodies: the voxel matrices, one policy each.
        settings: PPO's settings (`PpoSettings`).
        seed: decides the networks' initialisation and every sampled action and minibatch.
        episode_steps: the episode length (the task's default when None).
        precision: the simulation's real type (None: the process's).

    Returns:
        Each body's trained actor and training figures, in order.
    """
    torch = require_torch()
    if len(bodies) == 0:
        return []
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # one summation order: the same weights whatever the machine's cores
    try:
        with torch.random.fork_rng(devices=[]):
            return _train(torch, task, bodies, settings, seed, episode_steps, precision)
    finally:
        torch.set_num_threads(threads)


def _train(torch, task, bodies, s: PpoSettings, seed, episode_steps, precision) -> list[Trained]:
    B, E, T = len(bodies), s.n_envs, s.n_steps
    env = BatchEnv(task, [np.asarray(b) for b in bodies for _ in range(E)], episode_steps,
                   seeds=[seed + e for _ in bodies for e in range(E)], precision=precision)
    D, A = env.max_obs_dim, env.sim.max_actuators
    obs_dims, n_act = env.obs_dims[::E].copy(), env.n_actuators[::E].copy()
    gen = torch.Generator().manual_seed(int(seed))
    net = _Stack(torch, obs_dims, n_act, D, A, s.hidden, gen)
    opt = torch.optim.Adam(net.params, lr=s.learning_rate, eps=1e-5, fused=True)
    mask = torch.as_tensor(np.arange(A)[None, :] < n_act[:, None], dtype=torch.float32)[:, None, :]  # (B,1,A)
    half_log_2pi = 0.5 * math.log(2 * math.pi)

    def log_prob(mu, actions):
        log_std = net.log_std
        z = (actions - mu) / log_std.exp()
        return ((-0.5 * z * z - log_std - half_log_2pi) * mask).sum(-1)

    def as_batch(o: np.ndarray):
        return torch.as_tensor(np.nan_to_num(o, nan=0.0, posinf=0.0, neginf=0.0).reshape(B, E, D),
                               dtype=torch.float32)

    obs = as_batch(env.observe())
    starts = torch.ones((B, E))
    returns_now = np.zeros(B * E)
    finished: list[list[float]] = [[] for _ in range(B)]
    buf_obs = torch.zeros((T, B, E, D))
    buf_act = torch.zeros((T, B, E, A))
    buf_logp, buf_val, buf_rew, buf_start = (torch.zeros((T, B, E)) for _ in range(4))
    for _ in range(s.updates):
        with torch.no_grad():
            for t in range(T):
                mu, v = net.forward(obs)
                a = mu + net.log_std.exp() * torch.randn(mu.shape, generator=gen)
                buf_obs[t], buf_act[t], buf_val[t], buf_start[t] = obs, a, v, starts
                buf_logp[t] = log_prob(mu, a)
                step = a.clamp(ACTION_LOW, ACTION_HIGH).reshape(B * E, A).numpy().astype(np.float64)
                o, r, term, trunc, _ = env.step(step)
                r = np.nan_to_num(np.asarray(r, dtype=np.float64), nan=0.0)
                returns_now += r
                done = term | trunc
                rew = torch.as_tensor(r.reshape(B, E), dtype=torch.float32)
                if done.any():
                    cut = trunc & ~term
                    if cut.any():  # bootstrap a time limit's cut with the final observation's value
                        _, v_end = net.forward(as_batch(o))
                        rew = rew + s.gamma * v_end * torch.as_tensor(cut.reshape(B, E), dtype=torch.float32)
                    for w in np.flatnonzero(done):
                        finished[w // E].append(float(returns_now[w]))
                    returns_now[done] = 0.0
                    o = env.reset(mask=done)
                buf_rew[t] = rew
                obs = as_batch(o)
                starts = torch.as_tensor(done.reshape(B, E), dtype=torch.float32)
            _, last_v = net.forward(obs)
            adv = torch.zeros((T, B, E))
            gae = torch.zeros((B, E))
            for t in reversed(range(T)):
                if t == T - 1:
                    nxt_v, nxt_live = last_v, 1.0 - starts
                else:
                    nxt_v, nxt_live = buf_val[t + 1], 1.0 - buf_start[t + 1]
                delta = buf_rew[t] + s.gamma * nxt_v * nxt_live - buf_val[t]
                gae = delta + s.gamma * s.gae_lambda * nxt_live * gae
                adv[t] = gae
            ret = adv + buf_val
        # (B, N, ...) with N = T x E samples per body, in SB3's order (step-major)
        flat = [x.transpose(0, 1).reshape(B, T * E, *x.shape[3:]) for x in (buf_obs, buf_act)]
        f_obs, f_act = flat
        f_logp, f_adv, f_ret = (x.transpose(0, 1).reshape(B, T * E) for x in (buf_logp, adv, ret))
        N = T * E
        for _ in range(s.n_epochs):
            perm = torch.randperm(N, generator=gen)
            for lo in range(0, N, s.batch_size):
                idx = perm[lo:lo + s.batch_size]
                mu, v = net.forward(f_obs[:, idx])
                lp = log_prob(mu, f_act[:, idx])
                a_ = f_adv[:, idx]
                if a_.shape[1] > 1:
                    a_ = (a_ - a_.mean(1, keepdim=True)) / (a_.std(1, keepdim=True) + 1e-8)
                ratio = (lp - f_logp[:, idx]).exp()
                pg = -torch.min(a_ * ratio, a_ * ratio.clamp(1 - s.clip_range, 1 + s.clip_range)).mean(1)
                vloss = ((f_ret[:, idx] - v) ** 2).mean(1)
                entropy = ((0.5 + half_log_2pi + net.log_std) * mask).sum(-1)[:, 0]
                loss = (pg - s.ent_coef * entropy + s.vf_coef * vloss).sum()
                opt.zero_grad()
                loss.backward()
                with torch.no_grad():  # each body's gradient clipped by its own norm (SB3: one model's)
                    net.clip_grads(s.max_grad_norm)
                opt.step()
    steps = s.updates * T * E
    return [Trained(net.actor(b, int(obs_dims[b]), int(n_act[b])), steps, len(finished[b]),
                    float(np.mean(finished[b][-10:])) if finished[b] else math.nan) for b in range(B)]
