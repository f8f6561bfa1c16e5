"""Write the packaged per-task configs, configs/<method>/<task>.yaml (sgr, direct, nested, map-elites,
ga-ppo), for every one of sgr's 32 tasks from one template per method (a developer tool: it is not installed).

Every config of a method is the same template with the task's name and episode length filled in:
the paper's settings (generations 250; SGR and direct NEAT 128 genomes, nested NEAT 12 bodies x 12
controllers; 5x5 bodies) and the honest evaluation every packaged config evolves under
(docs/EVOLVE.md "Robust evaluation"). The episode length: the SGR paper's four tasks (Walker-v0,
ObstacleTraverser-v1, Climber-v2, Thrower-v0) keep `episode_steps: null`, the paper's length; the
other 28 are not in the paper and get evogym's registered max_episode_steps
(`TaskSpec.evogym_steps`), written out.

Hand-written variants (quick.yaml, <task>-10x10.yaml, direct/<task>-per-cell.yaml) are not
generated. tests/evolve/runs/test_packaged_configs.py checks that the committed files are what
this script writes, so edit the templates here and run:

    python tools/gen_configs.py          # rewrite the files
    python tools/gen_configs.py --check  # exit 1 naming the files that differ
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from string import Template

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tasks.specs import BUILTIN, TASKS  # noqa: E402

PAPER_TASKS = ("Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0")  # the SGR paper's
METHODS = ("sgr", "direct", "nested", "map-elites", "ga-ppo")

# the honest evaluation of docs/EVOLVE.md "Robust evaluation", as every packaged config has it
ROBUST_ACCUMULATED = """\
# Honest by default (docs/EVOLVE.md "Robust evaluation"): every action carries uniform(±1e-3)
# actuator noise; one fresh episode per genome and generation, a survivor's fitness the mean of its
# scores so far (8 at most, then it is not simulated again: settle); the champion chosen at the end \
among the final elites (final_selection; auto: sized to at most a fifth of the run's episodes). For the
# paper's nominal evaluation (knife-edge champions) set both to null, as configs/sweeps/paper.yaml does.
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true, accumulate: true, settle: 8}
final_selection: {candidates: auto, episodes: auto, statistic: mean, tolerance: 0.05, rank: pooled, \
confirm: auto, holdout: auto}
"""

TEMPLATES = {
    "sgr": """\
# SGR (single genome, HyperNEAT-decoded body + controller) on $task$about
method: sgr
task: $task
generations: 250
pop_size: 128
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/sgr.ini
cppn_outputs: 1              # 1 as in the paper; 2 = separate body / controller outputs
weight_threshold: 0.2
max_weight: 1.0
body_distance_weight: 0.1    # v of the paper's eq. 1 (our choice, see docs/EVOLVE.md)
body_decoder: substrate      # the paper's; or cppn, fourier, growth (docs/EVOLVE.md "Body decoders")
checkpoint_every: 5
render_champion: true
""" + ROBUST_ACCUMULATED,
    "direct": """\
# Direct-encoding NEAT baseline on $task$about
method: direct
task: $task
generations: 250
pop_size: 128
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/direct.ini
body_distance_weight: 0.0    # plain NEAT speciation, as in the paper's baseline
checkpoint_every: 5
render_champion: true
""" + ROBUST_ACCUMULATED,
    "nested": """\
# Nested-loop NEAT baseline on $task$about
method: nested
task: $task
generations: 250
pop_size: 12                 # outer population (bodies), as in the paper
inner_pop_size: 12           # controllers per body, as in the paper
inner_generations: 2         # inner generations per outer generation (paper silent; our choice)
inner_keep_generations: 20   # forget a body's inner population after 20 outer generations without it
                             # (the champion's is kept; a body back later starts afresh; null = never
                             # forget: memory and checkpoints grow with every body seen; docs/EVOLVE.md)
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/nested-body.ini
controller_neat_config: ../neat/nested-controller.ini
checkpoint_every: 5
render_champion: true
# Honest by default (docs/EVOLVE.md "Robust evaluation"): every action carries uniform(±1e-3)
# actuator noise, one fresh episode per controller and evaluation (averaging and final selection are
# not for nested NEAT: a body's fitness is the best its inner search has found). For the paper's
# nominal evaluation set it to null, as configs/sweeps/paper.yaml does.
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true}
""",
    "map-elites": """\
# MAP-Elites with SGR genomes on $task$about
method: map-elites
task: $task
# The budget of SGR's 100 generations of configs/sgr/<task>.yaml: those runs simulated 8,109 to 9,107
# episodes (mean 8,648; results/robust-fast/runs/sgr-*/generations.csv, column episodes). Here a
# generation simulates its 64 valid children and re-scores at most 24 elites: at most 88 episodes, at
# most 8,800 in 100 generations (fewer while the archive is small).
generations: 100
pop_size: 128                # sizes the final selection alone, as SGR's 128 genomes do
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/sgr.ini  # NEAT's crossover and mutation; no speciation
cppn_outputs: 1
weight_threshold: 0.2
max_weight: 1.0
checkpoint_every: 5
render_champion: true
qd:
  descriptors: [actuator, rigid]  # the body's voxel shares; or behaviour: [gait_frequency, contact]
  resolution: [10, 10]            # cells per descriptor
  batch: 64                       # valid children per generation
  initial: 64                     # valid random genomes of the first generation
  rescore: 24                     # elites re-scored per generation at most (fewest scores first)
  selection: curiosity            # parents: elites whose children entered the archive drawn more often
  exploit: 0.5                    # half the children: parents the fittest of 4 elites drawn
  score_offset: auto              # the QD score counts fitness above the task's floor (qd_floors.py)
# Honest by default (docs/EVOLVE.md "Robust evaluation"): every action carries uniform(±1e-3)
# actuator noise; one episode per child, an elite's fitness the mean of its scores so far (re-scored
# until it has 8: settle); the champion chosen at the end among the archive's best elites
# (final_selection; auto: sized to at most a fifth of pop_size x generations episodes).
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true, accumulate: true, settle: 8}
final_selection: {candidates: auto, episodes: auto, statistic: mean, tolerance: 0.05, rank: pooled, \
confirm: auto, holdout: auto}
""",
    "ga-ppo": """\
# evogym's GA co-design on $task$about
# All of a generation's new bodies train together in one batched simulation, each with its own
# policy (docs/RL.md "Co-design with PPO").
method: ga-ppo
task: $task
generations: 20
pop_size: 16                 # bodies per generation; the best survive untrained, mutants fill the rest
seed: 0
robot_shape: [5, 5]
$episode
checkpoint_every: 1          # a generation trains for long: a checkpoint after each
render_champion: true
ga:
  mutation_rate: 0.1         # evogym's: each voxel redrawn with this probability
  survival: 0.6              # the first survivors' fraction, falling linearly to 0 (at least 2)
  max_evaluations: null      # null: it falls over the generations; N: over N bodies (evogym's run_ga.py)
ppo:                         # evogym's PPO arguments (examples/ppo/args.py), per body
  timesteps: 1000000         # 16 new bodies: ~2.7 h on a 2-vCPU VM (docs/BENCHMARKS.md, "GA + PPO")
  n_envs: 1
  n_steps: 128
  batch_size: 4
  n_epochs: 4
  learning_rate: 0.00025
  gamma: 0.99
  gae_lambda: 0.95
  clip_range: 0.1
  ent_coef: 0.01
  vf_coef: 0.5
  max_grad_norm: 0.5
  hidden: [64, 64]           # SB3's MlpPolicy: policy and value networks of two 64-unit tanh layers
# Honest by default (docs/EVOLVE.md "Robust evaluation"): a body's fitness is its trained policy's
# deterministic episode under uniform(±1e-3) actuator noise, a survivor's the mean of its scores so far
# (8 at most: settle); the champion chosen at the end among the final population (final_selection).
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true, accumulate: true, settle: 8}
final_selection: {candidates: auto, episodes: auto, statistic: mean, tolerance: 0.05, rank: pooled, \
confirm: auto, holdout: auto}
""",
}

# what each method's first line says of it, after the task's name
ABOUT = {
    "sgr": (" with the paper's settings.",
            " (not in the SGR paper) with the paper's settings\n# and evogym's episode length."),
    "direct": (" (one network: body coordinates + observation -> materials + actions).",
               " (not in the SGR paper; one network: body coordinates + observation -> materials\n"
               "# + actions) with the paper's settings and evogym's episode length."),
    "nested": (": outer NEAT over body networks, inner NEAT over controllers per body.",
               " (not in the SGR paper): outer NEAT over body networks, inner NEAT over\n"
               "# controllers per body; the paper's settings and evogym's episode length."),
    "ga-ppo": (": bodies by a genetic algorithm, each body's controller trained by PPO\n"
               "# (evogym's examples/ga with its PPO arguments; evogym's episode length).",
               ": bodies by a genetic algorithm, each body's controller trained by PPO\n"
               "# (evogym's examples/ga with its PPO arguments; evogym's episode length)."),
    "map-elites": (": an archive of the best robot per kind of body (docs/EVOLVE.md).",
                   " (not in the SGR paper): an archive of the best robot per kind of body\n"
                   "# (docs/EVOLVE.md); evogym's episode length."),
}
PAPER_EPISODE = {
    "sgr": "episode_steps: null          # null = the paper's episode length for the task",
    "direct": "episode_steps: null          # the paper's episode length",
    "nested": "episode_steps: null          # the paper's episode length",
    "map-elites": "episode_steps: null          # the paper's episode length",
}


def render(method: str, task: str) -> str:
    """The text of configs/<method>/<task>.yaml."""
    paper = task in PAPER_TASKS
    episode = (PAPER_EPISODE[method] if paper and method in PAPER_EPISODE else
               f"episode_steps: {TASKS[task].evogym_steps:<19}# evogym's max_episode_steps for {task}")
    return Template(TEMPLATES[method]).substitute(task=task, about=ABOUT[method][0 if paper else 1],
                                                  episode=episode)


def generated() -> dict[Path, str]:
    """Every generated config: its path under configs/ -> its text."""
    return {Path(method) / f"{task}.yaml": render(method, task)
            for method in METHODS for task in sorted(BUILTIN)}


def main(argv: list[str] | None = None) -> int:
    """Write the configs (or, with --check, list those that differ from the templates)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="write nothing; exit 1 if a file differs")
    p.add_argument("--out", type=Path, default=ROOT / "configs", help="the configs folder")
    args = p.parse_args(argv)
    stale = []
    for rel, text in generated().items():
        path = args.out / rel
        if path.is_file() and path.read_text() == text:
            continue
        stale.append(str(rel))
        if not args.check:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
    if args.check and stale:
        print(f"{len(stale)} configs differ from tools/gen_configs.py's templates: {', '.join(stale)}; "
              "run python tools/gen_configs.py", file=sys.stderr)
        return 1
    print(f"{'checked' if args.check else 'wrote'} {len(stale) if not args.check else len(generated())} "
          f"configs in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
