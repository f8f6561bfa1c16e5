"""`sgr evolve`: start a run (a config file, a packaged config, or a method on a task) or resume one."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

from evolve.cli.common import add_workers, output_path, parse_shape, positive, resume_dir
from tasks.cli import PRECISIONS
from tasks.specs import MAX_STEPS
from tsim.errors import SgrError


def register(sub) -> argparse.ArgumentParser:
    """Add `evolve` to the dispatcher's subparsers."""
    e = sub.add_parser("evolve", help="run an evolution experiment (default: a short SGR Walker-v0 run)")
    e.add_argument("--config", help="YAML experiment config: a file, or a packaged config's name such as "
                                    "sgr/Climber-v2 or direct/Walker-v0 (default: quick, a short SGR "
                                    "Walker-v0 run)")
    e.add_argument("--task", help="the packaged config of this task (with --method; default method sgr)")
    e.add_argument("--method", help="with --task: sgr, direct, nested, map-elites or ga-ppo")
    e.add_argument("--shape", metavar="RxC",
                   help="the body grid, rows x columns (e.g. 10x10): with --task the packaged "
                        "<task>-RxC config when there is one, else the task's config at this size")
    e.add_argument("--body-decoder", metavar="NAME",
                   help="how an sgr genome draws its body (config key body_decoder): substrate (the paper's, "
                        "default), cppn, fourier or growth (docs/EVOLVE.md \"Body decoders\")")
    e.add_argument("--from", dest="start_from", metavar="RUN",
                   help="a new run that starts from RUN's population (its newest checkpoint), with "
                        "RUN's config (sgr; with --shape: at another size; --generations counts from "
                        "RUN's start, default twice RUN's generations so far)")
    e.add_argument("--generations", type=positive(int),
                   help="generations to run (config key generations); with --resume: extend the run to N")
    e.add_argument("--pop", type=positive(int), help="genomes per generation (config key pop_size)")
    e.add_argument("--seed", type=int, help="the run's seed (config key seed): the same seed, config and "
                                            "sgr give the same run")
    e.add_argument("--episode-steps", type=positive(int, MAX_STEPS), metavar="N",
                   help="steps of each episode (config key episode_steps; default: the config's, else the "
                        "task's paper length): shorter episodes for a quick try")
    e.add_argument("--out", help="run directory (default runs/<method>-<config>-seed<S>-<time>)")
    add_workers(e, None, "rollout processes: a number, 'auto' (all CPUs) or 'ray' (the actors of a Ray "
                         "cluster); default: the config's")
    e.add_argument("--resume", metavar="DIR",
                   help="continue a run from its last checkpoint (with --generations N: extend it to N)")
    e.add_argument("--precision", choices=PRECISIONS,
                   help="the simulator's real type: f64 (evogym's bits) or f32; default: the config's, "
                        "else $SGR_PRECISION, else f64")
    e.add_argument("--tensorboard", action="store_true", default=None,
                   help="TensorBoard events of each generation's scalars in RUN/tensorboard (config key "
                        "tensorboard: true; needs pip install 'sgr[tensorboard]'); with --resume: for "
                        "this resumed part of the run")
    e.add_argument("--quiet", action="store_true", help="no line per generation")
    e.set_defaults(fn=run)
    return e


DEFAULTS_PREFIX = "sgr-config-"  # the temporary folder of a method's default_config


def _made_config(config: Path) -> Path | None:
    """The temporary folder `evolve_config` made for a method's defaults, when `config` is in one."""
    import tempfile

    folder = config.parent
    made = folder.name.startswith(DEFAULTS_PREFIX) and folder.parent == Path(tempfile.gettempdir())
    return folder if made else None


def evolve_config(args: argparse.Namespace, shape: tuple[int, int] | None = None) -> Path:
    """The config a new run starts from: --config (a file, or a packaged config's name), the
    packaged config of --method on --task (at `shape`: its <task>-RxC config when one ships, else
    its config, whose robot_shape the caller overrides), or the default quick run."""
    from evolve.methods import METHODS
    from evolve.runs.config import configs_dir, find_config
    from tasks.specs import TASKS, unknown_name, unknown_task

    if args.task == "" or args.method == "":
        raise SgrError(f"--{'task' if args.task == '' else 'method'} needs a name, got an empty one")
    if args.config and (args.task or args.method):
        raise SgrError("give --config, or --task (with --method), not both")
    if args.config:
        return find_config(args.config)
    if args.method and not args.task:
        raise SgrError("--method goes with --task (e.g. sgr evolve --task Climber-v2 --method direct)")
    if not args.task:
        return configs_dir() / "sgr" / "quick.yaml"
    method = args.method or "sgr"
    if method not in METHODS:
        raise SgrError(unknown_name("method", method, METHODS) + " (a method of your own: --import FILE "
                       "with the module that registers it)")
    sized = configs_dir() / method / f"{args.task}-{shape[0]}x{shape[1]}.yaml" if shape else None
    if sized is not None and sized.is_file():
        return sized
    path = configs_dir() / method / f"{args.task}.yaml"
    if path.is_file():
        return path
    if args.task not in TASKS:
        raise SgrError(f"{unknown_task(args.task)} (a task of your own: --config FILE with "
                       "task: and imports:, docs/TASKS.md)")
    own = METHODS[method].default_config(args.task)  # a method of the user's: its own defaults
    if own is not None:
        import tempfile

        import yaml

        # (a folder of its own, which `run` removes once the run has copied it: _made_config)
        path = Path(tempfile.mkdtemp(prefix=DEFAULTS_PREFIX)) / f"{args.task}.yaml"
        path.write_text(yaml.safe_dump({**own, "method": method, "task": args.task}, sort_keys=False))
        return path
    shipped = sorted(f.stem for f in (configs_dir() / method).glob("*.yaml"))
    raise SgrError(f"no packaged config for {method} on {args.task} (there are: {', '.join(shipped)}); "
                   "write one and give --config FILE")


def run(args: argparse.Namespace) -> int:
    """`sgr evolve`."""
    from evolve.runs.config import load_config
    from evolve.runs.experiment import Experiment, start_backend
    from tsim.backend import runtime

    runtime.requested_arch()  # a misspelt SGR_ARCH fails before a run directory exists
    runtime.requested_precision()  # and so does a misspelt SGR_PRECISION
    shape = parse_shape(args.shape) if args.shape is not None else None
    if args.resume:
        if (args.config or args.pop or args.seed is not None or args.out or args.task or args.method
                or args.precision or args.shape is not None or args.start_from or args.body_decoder
                or args.episode_steps):
            raise SgrError("--resume continues a run with its own config; only --generations "
                           "(to extend it), --workers, --trust-imports, --import, --tensorboard and --quiet "
                           "go with it")
        exp = Experiment.resume(resume_dir(args.resume), quiet=args.quiet, workers=args.workers,
                                generations=args.generations)
        print(runtime.describe())  # the backend it started (it records it: segments.json)
        print(f"resuming {args.resume} after generation {exp.search.generation}")
        if args.tensorboard and not exp.cfg.tensorboard:
            from evolve.runs.reporters import configured_reporters
            for reporter in configured_reporters(exp.cfg.replace(tensorboard=True), exp.run.path):
                exp.add_reporter(reporter)
    else:
        flags = {"generations": args.generations, "pop_size": args.pop, "seed": args.seed,
                 "workers": args.workers, "precision": args.precision, "tensorboard": args.tensorboard,
                 "robot_shape": list(shape) if shape else None, "body_decoder": args.body_decoder,
                 "episode_steps": args.episode_steps}
        overrides = {k: v for k, v in flags.items() if v is not None}  # the flags given
        if getattr(args, "import_files", None) and not args.config and not args.start_from:
            # --import FILE with --method: the user's module registers the method (or the task)
            from tasks.registry import import_tasks

            overrides["imports"] = [str(Path(f).resolve()) for f in args.import_files]
            for f in overrides["imports"]:
                import_tasks(f)
        if args.start_from:
            config, name = continuation(args, overrides)
        else:
            config, name = evolve_config(args, shape), None
        named_in = config if args.start_from else None  # read back from a run folder: data
        if args.body_decoder:
            rest = {k: v for k, v in overrides.items() if k != "body_decoder"}
            _check_body_decoder(load_config(config, rest, named_in).method)
        cfg = load_config(config, overrides, named_in)
        # the first line names the backend; one that cannot start fails here, before the run exists
        print(start_backend(cfg.precision).line(), flush=True)
        if name is None:
            name = f"{cfg.method}-{config.stem}" if config.stem != cfg.method else config.stem
            if shape and not config.stem.endswith(f"-{shape[0]}x{shape[1]}"):
                name += f"-{shape[0]}x{shape[1]}"
            if args.body_decoder:
                name += f"-{args.body_decoder}"
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out = args.out or str(Path("runs") / f"{name}-seed{cfg.seed}-{stamp}")
        output_path(out, folder=True)
        try:
            exp = Experiment.create(config, out, overrides, quiet=args.quiet, named_in=named_in)
        finally:  # the run keeps its own copy (config.yaml)
            if (made := _made_config(config)) is not None:
                import shutil

                shutil.rmtree(made, ignore_errors=True)
        print(f"run directory: {out}")
    return run_experiment(exp)


def continuation(args: argparse.Namespace, overrides: dict) -> tuple[Path, str]:
    """`--from RUN`: the config (RUN's config.yaml) and the default folder name of a run that starts
    from RUN's newest checkpoint; `overrides` gains start_from and, when not given, generations
    (twice RUN's generations so far)."""
    from evolve.records.rundir import RunDir

    if args.config or args.task or args.method:
        raise SgrError("--from starts from another run's config and population; --config, --task and "
                       "--method do not go with it")
    src = RunDir(resume_dir(args.start_from))
    # a run folder, or one line saying it is not; its task known (its code run only with --trust-imports)
    src.load_task(src.config())
    done = src.last_checkpoint_generation()
    if done is None:
        raise SgrError(f"--from {args.start_from}: the run has no checkpoint to start from")
    overrides["start_from"] = {"run": str(src.path.resolve())}
    if overrides.get("generations") is None:
        overrides["generations"] = 2 * max(done, 1)
    shape = overrides.get("robot_shape")
    size = f"-{shape[0]}x{shape[1]}" if shape else ""
    decoder = f"-{args.body_decoder}" if args.body_decoder else ""
    return src.path / "config.yaml", f"{src.path.name}-from{done}{size}{decoder}"


def run_experiment(exp) -> int:
    """Run `exp` to its end; a stop (Ctrl-C, SIGTERM, a dead worker, a full disk) says how to resume.
    A stop by a signal exits 128 + its number: 130 for Ctrl-C, 143 for SIGTERM (evolve/runs/stops.py)."""
    from evolve.rollout.pool import WorkerDied
    from evolve.runs.stops import exit_code

    try:
        with exp:
            exp.run_all()
            exp.finish()
    except KeyboardInterrupt as exc:
        done, want = exp.search.generation, exp.cfg.generations
        ckpt = exp.run.last_checkpoint_generation()
        if getattr(exc, "at_once", False) and ckpt is not None:  # a second signal: the generation after
            done = ckpt  # the checkpoint (of the last finished one) was cut short
        where = (f"stopped after generation {done} of {want}, with a checkpoint" if ckpt == done
                 and not getattr(exc, "at_once", False) else
                 f"stopped during generation {done + 1} of {want}; its last checkpoint is after "
                 f"generation {ckpt}")
        code = exit_code(exc)
        by = "" if code == 130 else f"{signal.Signals(code - 128).name}: "  # (Ctrl-C's words as ever)
        print(f"\nsgr: {by}{where}; continue with: sgr evolve --resume {exp.run.path}",
              file=sys.stderr)
        return code
    except WorkerDied as exc:
        print(f"sgr: error: {exc}; the run stopped during generation {exp.search.generation + 1} and "
              f"keeps its last checkpoint: sgr evolve --resume {exp.run.path}", file=sys.stderr)
        return 1
    except OSError as exc:  # e.g. a full disk: every file is still whole (a cut CSV row is dropped)
        print(f"sgr: error: {exp.write_failed(exc)}", file=sys.stderr)
        return 1
    return 0


def _check_body_decoder(method: str) -> None:
    """`--body-decoder` names the flag, not the config key, when the method draws no body from its
    genome (direct NEAT's genome is the body; nested's outer loop is direct's)."""
    from evolve.methods import METHODS

    if "body_decoder" not in METHODS[method].config_keys:
        having = ", ".join(n for n, p in METHODS.items() if "body_decoder" in p.config_keys)
        raise SgrError(f"--body-decoder is for the methods whose genome draws the body ({having}); "
                       f"method {method!r} has no body decoder")
