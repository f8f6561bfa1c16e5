"""The `sgr` dispatcher is built from one module per command, and an option that means the same
thing in two commands is typed the same way in both."""

import argparse

import pytest

from evolve.cli import build_parser


def _actions(parser: argparse.ArgumentParser) -> dict[str, dict[str, argparse.Action]]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: {opt: a for a in p._actions for opt in a.option_strings} for name, p in sub.choices.items()}


def test_every_command_is_registered():
    assert set(_actions(build_parser())) == {"evolve", "sweep", "report", "select-champion", "render", "plot",
                                             "migrate", "convert-checkpoints", "decode", "demo", "validate",
                                             "bench", "explain"}


def test_noise_and_workers_are_typed_the_same_way_in_every_command():
    cmds = _actions(build_parser())
    for opt in ("--noise", "--workers", "--trust-imports"):
        having = [c for c in cmds.values() if opt in c]
        assert len(having) >= 2, opt
        assert len({id(c[opt].type) for c in having}) == 1, opt


def test_noise_accepts_the_same_values_in_report_and_render():
    p = build_parser()
    assert p.parse_args(["report", "d", "--noise", "0", "1e-3"]).noise == [0.0, 1e-3]
    assert p.parse_args(["render", "d", "--noise", "0"]).noise == 0.0


def test_every_option_and_argument_of_every_command_says_what_it_does():
    """`sgr COMMAND --help` explains each option (a third-week user found --generations, --pop and
    --seed with empty help)."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    silent = [f"{parser.prog} {a.dest}" for a in parser._actions if not (a.help or "").strip()]
    for name, p in sub.choices.items():
        silent += [f"{name} {a.option_strings or a.dest}" for a in p._actions
                   if not (a.help or "").strip() and a.help is not argparse.SUPPRESS]
    assert not silent, silent


def test_episode_steps_is_an_option_of_evolve_and_refused_with_resume():
    p = build_parser()
    assert p.parse_args(["evolve", "--episode-steps", "50"]).episode_steps == 50
    assert p.parse_args(["evolve"]).episode_steps is None


@pytest.mark.slow
def test_evolve_with_episode_steps_runs_and_records_that_length(tmp_path, capsys):
    """`sgr evolve --episode-steps 50` runs without a YAML file, and the run records the length."""
    import yaml

    from evolve.cli import main

    out = tmp_path / "run"
    assert main(["evolve", "--episode-steps", "50", "--generations", "1", "--pop", "8", "--workers", "1",
                 "--out", str(out), "--quiet"]) == 0, capsys.readouterr().err
    assert yaml.safe_load((out / "config.yaml").read_text())["episode_steps"] == 50
    assert main(["evolve", "--resume", str(out), "--episode-steps", "60"]) == 2
    assert "--resume continues a run with its own config" in capsys.readouterr().err
