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
    """neat-python's Config of an INI file; errors name `source` (default: the file)."""
    try:
        return neat.Config(BodyAwareGenome, FlexibleReproduction, neat.DefaultSpeciesSet,
                           neat.DefaultStagnation, str(ini_path))
    except Exception as exc:  # neat-python raises RuntimeError/KeyError for bad INI keys
        what = " ".join(str(exc).split())  # one line
        raise SgrError(f"{source or ini_path}: bad neat-python config: {what}") from None


def neat_config_from_text(ini: str, source: str | Path | None = None) -> neat.Config:
    """neat-python reads configs only from files: load INI text through a temporary one; errors
    name `source`, the INI the text came from."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "neat.ini"
        path.write_text(ini)
        return load_neat_config(path, source or "neat config")
