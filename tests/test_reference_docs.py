"""The reference pages (docs/reference/cli.md, config.md) are what tools/gen_reference.py writes
from the code: a command, option or config key added or changed without regenerating them fails
here, so the pages cannot drift from `sgr` itself."""

import argparse
import importlib.util
import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "docs" / "reference"


def _generator():
    spec = importlib.util.spec_from_file_location("gen_reference", ROOT / "tools" / "gen_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_reference_pages_are_what_the_generator_writes():
    assert _generator().stale() == [], "run: python tools/gen_reference.py"


def test_a_hand_edited_or_missing_reference_page_is_found_stale(tmp_path):
    gen = _generator()
    shutil.copytree(REFERENCE, tmp_path, dirs_exist_ok=True)
    (tmp_path / "cli.md").write_text((tmp_path / "cli.md").read_text().replace("--resume", "--resum"))
    (tmp_path / "config.md").unlink()
    assert gen.stale(tmp_path) == ["cli.md", "config.md"]


def test_the_cli_page_has_a_section_for_every_sgr_command_and_each_of_its_options():
    from evolve.cli import build_parser

    page = (REFERENCE / "cli.md").read_text()
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    sections = dict(re.findall(r"^## `sgr ([\w-]+)`\n(.*?)(?=^## |\Z)", page, re.M | re.S))
    for name, parser in sub.choices.items():
        if name in sections:
            for action in parser._actions:
                for option in action.option_strings:
                    if option not in ("-h", "--help", "--debug"):
                        assert f"`{option}`" in sections[name], (name, option)
        else:
            assert f"`sgr {name}` is another name for" in page, name


def test_the_config_page_lists_every_common_key_and_every_methods_own_keys():
    from evolve.config import COMMON
    from evolve.methods import METHODS

    page = (REFERENCE / "config.md").read_text()
    common = page[page.index("## Common keys"):page.index("## `method:")]
    assert set(re.findall(r"^\| `(\w+)` \|", common, re.M)) == set(COMMON)
    for name, problem in METHODS.items():
        section = page.split(f"## `method: {name}`")[1].split("\n## ")[0]
        assert set(problem.config_keys) <= set(re.findall(r"^\| `(\w+)` \|", section, re.M)), name


def test_every_config_key_of_every_method_says_what_it_does():
    """docs/reference/config.md has a sentence for every key (it listed keys without saying what
    they do): the common keys' (evolve.config.KEY_DOCS) and each method's (`Problem.config_docs`)."""
    from evolve.config import COMMON, KEY_DOCS
    from evolve.methods import METHODS

    assert set(KEY_DOCS) == set(COMMON)
    for name, problem in METHODS.items():
        assert set(problem.config_docs) == set(problem.config_keys), name
    for text in [*KEY_DOCS.values(), *(t for p in METHODS.values() for t in p.config_docs.values())]:
        assert len(text.split()) >= 4 and text.endswith("."), text
    page = (REFERENCE / "config.md").read_text()
    assert page.count("| what it does |") == 1 + len(METHODS) - sum(
        not p.config_keys and not p.default_files for p in METHODS.values())
