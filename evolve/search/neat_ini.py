"""neat-python configs: our INI files made into neat-python's `Config` with our genome and
reproduction classes, and errors that name the user's file in one line."""

from __future__ import annotations

import ast
import configparser
import contextlib
import io
import tempfile
from pathlib import Path

import neat

from evolve.nn.genome_record import MAX_GENOME_NODES, MAX_POP
from evolve.search.genome import BodyAwareGenome, FlexibleReproduction
from tsim.errors import SgrError

SECTIONS = {"DefaultGenome": BodyAwareGenome.__name__,
            "DefaultReproduction": FlexibleReproduction.__name__}


def ini_problem(exc: configparser.Error) -> str:
    """One line for an INI syntax error (configparser's own messages span several lines)."""
    if isinstance(exc, configparser.MissingSectionHeaderError):
        return f"line {exc.lineno}: {exc.line.strip()!r} comes before any [section] header"
    if isinstance(exc, configparser.ParsingError):
        lineno, line = exc.errors[0]
        with contextlib.suppress(ValueError, SyntaxError):
            line = ast.literal_eval(line)  # configparser stores the repr of the line
        return f"line {lineno}: cannot parse {str(line).strip()!r} (not 'key = value')"
    if isinstance(exc, configparser.DuplicateSectionError):
        return f"line {exc.lineno}: section [{exc.section}] appears twice"
    if isinstance(exc, configparser.DuplicateOptionError):
        return f"line {exc.lineno}: key {exc.option!r} appears twice in [{exc.section}]"
    return " ".join(str(exc).split())


def neat_ini_text(path: str, pop_size: int, overrides: dict) -> str:
    """The neat-python INI with the config's `pop_size` and method-specific values (`overrides`)."""
    cp = configparser.ConfigParser()
    try:
        if not cp.read(path):
            raise SgrError(f"{path}: neat config file not found")
    except configparser.Error as exc:
        raise SgrError(f"{path}: not a valid INI file: {ini_problem(exc)}") from None
    except UnicodeDecodeError:
        raise SgrError(f"{path}: not a valid INI file: not text") from None
    for section in ("NEAT", *SECTIONS):
        if section not in cp:
            raise SgrError(f"{path}: neat config lacks the [{section}] section")
    cp["NEAT"]["pop_size"] = str(pop_size)
    # neat-python reads each section under its class's name
    for default, ours in SECTIONS.items():
        cp[ours] = dict(cp[default])
        cp.remove_section(default)
    for section, values in overrides.items():
        for k, v in values.items():
            cp[SECTIONS.get(section, section)][k] = v
    buf = io.StringIO()
    cp.write(buf)
    return buf.getvalue()


def load_neat_config(ini_path: Path, source: str | Path | None = None) -> neat.Config:
    """neat-python's Config of an INI file, its sizes checked (`check_sizes`); errors name
    `source` (default: the file)."""
    _check_numbers(ini_path, source or ini_path)
    try:
        config = neat.Config(BodyAwareGenome, FlexibleReproduction, neat.DefaultSpeciesSet,
                             neat.DefaultStagnation, str(ini_path))
    except Exception as exc:  # neat-python raises RuntimeError/KeyError for bad INI keys
        what = " ".join(str(exc).split())  # one line
        raise SgrError(f"{source or ini_path}: bad neat-python config: {what}") from None
    check_sizes(config, source or ini_path)
    return config


# the INI's numbers that size what neat-python builds: each named when it is not a number
NUMBER_KEYS = {"NEAT": {"pop_size": int, "fitness_threshold": float},
               BodyAwareGenome.__name__: {"num_inputs": int, "num_outputs": int, "num_hidden": int}}


def _check_numbers(ini_path: Path, source: str | Path) -> None:
    """SgrError naming `source` and the key when one of NUMBER_KEYS is not a number of its type
    (neat-python's own error names the value only); anything else is left to neat-python."""
    cp = configparser.ConfigParser()
    try:
        cp.read(ini_path)
    except (configparser.Error, UnicodeDecodeError):
        return  # neat-python says why, below
    for section, keys in NUMBER_KEYS.items():
        for key, kind in keys.items():
            text = cp[section].get(key) if section in cp else None
            if text is None:
                continue
            try:
                kind(text)
            except ValueError:
                raise SgrError(f"{source}: key {key!r} must be {'an int' if kind is int else 'a number'}, "
                               f"got {text[:40]!r}") from None


def check_sizes(config: neat.Config, source: str | Path) -> None:
    """SgrError naming `source` and the key unless the INI's population and genome sizes are in
    bounds: pop_size 1..MAX_POP (as the YAML config's), the pins and initial hidden nodes of a
    genome within what sgr reads back of one (evolve/nn/genome_record.py), fitness_threshold
    a number. A new run's INI and a run folder's neat.ini (a stranger's) are checked alike."""
    gc = config.genome_config
    bounds = (("pop_size", config.pop_size, 1, MAX_POP),
              ("num_inputs", gc.num_inputs, 1, MAX_GENOME_NODES),
              ("num_outputs", gc.num_outputs, 1, MAX_GENOME_NODES),
              ("num_hidden", gc.num_hidden, 0, MAX_GENOME_NODES - gc.num_outputs))
    for key, value, least, most in bounds:
        if not isinstance(value, int) or not least <= value <= max(least, most):
            raise SgrError(f"{source}: key {key!r} must be an int from {least:,} to {max(least, most):,}, "
                           f"got {value!r}")
    threshold = config.fitness_threshold
    if not isinstance(threshold, float) or threshold != threshold:
        raise SgrError(f"{source}: key 'fitness_threshold' must be a number, got {threshold!r}")


def neat_config_from_text(ini: str, source: str | Path | None = None) -> neat.Config:
    """neat-python reads configs only from files: load INI text through a temporary one; errors
    name `source`, the INI the text came from."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "neat.ini"
        path.write_text(ini)
        return load_neat_config(path, source or "neat config")
