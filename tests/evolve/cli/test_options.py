"""The `sgr` dispatcher is built from one module per command, and an option that means the same
thing in two commands is typed the same way in both."""

import argparse

from evolve.cli import build_parser


def _actions(parser: argparse.ArgumentParser) -> dict[str, dict[str, argparse.Action]]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: {opt: a for a in p._actions for opt in a.option_strings} for name, p in sub.choices.items()}


def test_every_command_is_registered():
    assert set(_actions(build_parser())) == {"evolve", "sweep", "report", "select-champion", "render", "plot",
                                             "migrate", "convert-checkpoints", "decode", "demo", "validate",
                                             "bench"}


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
