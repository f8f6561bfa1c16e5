"""The docs' facts, not only their headings.

1. Every figure in a "Today" section that links to a record (`[6.70](records/host-costs.json#sample)`)
   shows the record's value(s), to the digits it prints; every figure cell of a Today table carries
   such a link. A record (docs/records/*.json) is what a benchmark or study wrote, with the machine,
   the commit, the date and the command (`sgr bench --record`, `python bench/... --record`).
2. Every file path and `sgr` command named in README.md, docs/**/*.md and results/*/README.md
   exists: a backticked `bench/x.py`, `configs/...`, `docs/...` is a file of the repository
   (`../shared/...`: of the shared folder beside it), and `sgr <command>` is a command of the CLI's
   parser.
3. Every option on a command line there is one its command takes (`sgr <command> --opt`, `python
   bench/x.py --opt`), and a script's required options are given.
"""

import json
import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
RECORDS = DOCS / "records"
SHARED = ROOT.parent / "shared"
# docs/reference and docs/history too, and the README of every results folder (how its runs were made)
PAGES = [ROOT / "README.md", *sorted(DOCS.rglob("*.md")), *sorted((ROOT / "results").glob("*/README.md"))]
TODAY = {"BENCHMARKS.md": "Today's figures, per machine", "VALIDATION.md": "Today", "RESULTS.md": "Today"}
RECORD_KEYS = {"name", "figures", "machine", "commit", "date", "command"}

LINK = re.compile(r"\[([^\]]*)\]\((?:docs/|\.\./)?records/([\w.-]+\.json)#([\w.-]+)\)")
NUMBER = re.compile(r"(?<![\w.])[-−]?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?")
# a path the docs name: a top-level folder of the repository (or ../shared), then a file or folder
PATH = re.compile(r"(?<![\w./-])((?:\.\./shared|bench|references|studies|device|results|tools|configs|docs|"
                  r"tests|tsim|tasks|evolve|examples)"
                  r"/[\w./*-]*[\w/*])")
SPAN = re.compile(r"`([^`\n]+)`")
# files a how-to asks the reader to write (they are the reader's, not the repository's)
THE_READERS = {"tasks/suite/hopper.py": "TASKS.md: how to add a task"}
# `sgr CMD` at the start of a command line (after `VAR=value`s, `&&`, `|`), not `sgr` in prose
COMMAND = re.compile(r"(?:^|(?:&&|\|)\s*)(?:[A-Z_]+=\S*\s+)*sgr\s+([a-z][\w-]*)")
# `python SCRIPT.py` of the repository's scripts, and an option on a command line
SCRIPT = re.compile(r"(?:[A-Z_]+=\S*\s+)*(?:\S*/)?python3?\s+"
                    r"((?:bench|studies|tools|device|references|examples)/[\w/]+\.py)")
OPTION = re.compile(r"(?<![\w-])(--[a-z][\w-]*)")


def section(text: str, heading: str) -> str:
    """The text under `## heading`, up to the next `## `."""
    start = text.index(f"\n## {heading}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else len(text)]


def numbers(text: str) -> list[float]:
    return [float(n.replace(",", "").replace("−", "-")) for n in NUMBER.findall(text)]


def shown(value: float, text: str) -> bool:
    """`text` (one number as printed) is `value` to the digits it prints."""
    digits = len(text.split(".")[1]) if "." in text and "e" not in text.lower() else 0
    printed = float(text.replace(",", "").replace("−", "-"))
    if "e" in text.lower():
        mantissa = text.lower().split("e")[0]
        digits = len(mantissa.split(".")[1]) if "." in mantissa else 0
        return abs(printed - value) <= 0.5 * 10 ** (int(text.lower().split("e")[1]) - digits) * 1.0001
    return abs(printed - value) <= 0.5 * 10 ** -digits + 1e-12


def load(name: str) -> dict:
    return json.loads((RECORDS / name).read_text())


def figure_values(record: dict, key: str) -> list[float]:
    value = record["figures"][key]["value"]
    return [float(v) for v in (value if isinstance(value, list) else [value])]


def check_links(text: str) -> list[str]:
    """What disagrees between the record links in `text` and their records."""
    wrong = []
    for shown_text, name, key in LINK.findall(text):
        if not (RECORDS / name).exists():
            wrong.append(f"{name}: no such record")
            continue
        record = load(name)
        if key not in record["figures"]:
            wrong.append(f"{name}#{key}: no such figure in the record")
            continue
        printed = NUMBER.findall(shown_text)
        values = figure_values(record, key)
        if len(printed) != len(values) or not all(map(shown, values, printed)):
            wrong.append(f"{name}#{key}: the doc shows {shown_text!r}, the record {values}")
    return wrong


def table_cells_without_a_record(text: str) -> list[str]:
    """Figure cells of the tables in `text` (every column but the first and a `command` one) that
    link to no record."""
    bare, header = [], None
    for line in text.splitlines():
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.replace("\\|", "/").strip().strip("|").split("|")]
        if header is None:
            header = cells
            continue
        if set(line) <= set("|-: "):
            continue
        for title, cell in zip(header[1:], cells[1:], strict=False):
            if title.lower() != "command" and re.search(r"\d", cell) and not LINK.search(cell):
                bare.append(f"{cells[0]} / {title}: {cell}")
    return bare


@pytest.mark.parametrize("doc", sorted(TODAY))
def test_every_figure_of_today_shows_its_records_value(doc):
    today = section((DOCS / doc).read_text(), TODAY[doc])
    assert LINK.search(today), f"{doc}: no figure of Today links to its record"
    wrong = check_links(today)
    assert not wrong, f"{doc}: {wrong}"
    assert not table_cells_without_a_record(today), f"{doc}: figures without a record"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_figure_a_page_links_to_a_record_shows_its_value(page):
    """README's figures too (and any page's, beyond Today)."""
    wrong = check_links(page.read_text())
    assert not wrong, f"{page.name}: {wrong}"


def test_every_record_says_where_and_how_it_was_measured():
    records = sorted(RECORDS.glob("*.json"))
    assert records
    for path in records:
        record = json.loads(path.read_text())
        assert RECORD_KEYS <= set(record), (path.name, RECORD_KEYS - set(record))
        assert record["name"] == path.stem
        assert re.fullmatch(r"[0-9a-f]{7,40}", record["commit"]), (path.name, record["commit"])
        assert re.fullmatch(r"20\d\d-\d\d-\d\d.*", record["date"]), (path.name, record["date"])
        assert record["machine"] and record["command"]
        for key, figure in record["figures"].items():
            assert "unit" in figure and figure_values(record, key), (path.name, key)


def test_a_figure_that_disagrees_with_its_record_is_found():
    """The checks above can fail: a figure one off, a missing figure or record, a bare table cell."""
    name, key, value = next((path.name, key, figure["value"]) for path in sorted(RECORDS.glob("*.json"))
                            for key, figure in json.loads(path.read_text())["figures"].items()
                            if isinstance(figure["value"], int | float) and figure["value"] >= 1)
    assert not check_links(f"[{value:,}](records/{name}#{key})")
    assert check_links(f"[{value + 1:,}](records/{name}#{key})")
    assert check_links(f"[{value:,} and 7](records/{name}#{key})")
    assert check_links(f"[{value:,}](records/{name}#no-such-figure)")
    assert check_links(f"[{value:,}](records/no-such-record.json#{key})")
    assert table_cells_without_a_record("| what | sgr |\n|---|---|\n| x | 12.5 robot-steps/s |\n")
    linked = f"| what | sgr |\n|---|---|\n| x | [{value}](records/{name}#{key}) |\n"
    assert not table_cells_without_a_record(linked)


def spans(text: str) -> list[str]:
    """Inline code spans and the lines of fenced or indented code blocks."""
    out = []
    fenced = False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
            continue
        if fenced or line.startswith("    "):
            out.append(line.strip())
        else:
            out += SPAN.findall(line)
    return out


def named_paths(text: str) -> set[str]:
    found = set()
    for span in spans(text):
        for m in PATH.finditer(span):
            path = m.group(1)
            if re.match(r"-?[<{]", span[m.end():]):  # a pattern such as runs/sgr-<task>, not a path
                continue
            if not re.search(r"[*<>{}]|\.\.\.|[A-Z]{3,}_?[A-Z]*/|/[A-Z_]{3,}(?:/|$)", path):
                found.add(path.split("::")[0].rstrip("."))
    return found


def sgr_commands(text: str) -> set[str]:
    return {m for span in spans(text) for m in COMMAND.findall(span.strip().removeprefix("$ "))}


def command_lines(text: str) -> list[str]:
    """`spans`, with a code block's lines ending in a backslash joined to the next."""
    out: list[str] = []
    for line in spans(text):
        if out and out[-1].endswith("\\"):
            out[-1] = out[-1][:-1] + " " + line
        else:
            out.append(line)
    return out


def named_commands(text: str) -> list[tuple[str, set[str]]]:
    """(what, its options) of every `sgr CMD` or `python SCRIPT.py` command line: what is
    "sgr CMD" or the script's path, the options every `--option` written after it on the same
    command (up to `&&`, `|` or `;`)."""
    found = []
    for line in command_lines(text):
        for part in re.split(r"&&|\|\||;|\|", line.strip().removeprefix("$ ")):
            m = COMMAND.match(part.strip()) or SCRIPT.match(part.strip())
            if m is not None:
                what = f"sgr {m.group(1)}" if m.re is COMMAND else m.group(1)
                found.append((what, set(OPTION.findall(part.strip()[m.end():]))))
    return found


def sgr_options() -> dict[str, set[str]]:
    """"sgr CMD" -> the options its parser takes (each also takes the top level's, --help and
    --debug)."""
    from evolve.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "cmd")
    return {f"sgr {name}": {o for a in p._actions for o in a.option_strings}
            for name, p in sub.choices.items()}


def script_options(path: Path) -> tuple[set[str], set[str]] | None:
    """(the options, the required ones) a script's argparse parser declares, read from its source
    (reading runs no code); None where it declares none (it reads its arguments another way)."""
    import ast

    options, required = set(), set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "add_argument":
            names = {a.value for a in node.args
                     if isinstance(a, ast.Constant) and str(a.value).startswith("--")}
            options |= names
            if any(k.arg == "required" and getattr(k.value, "value", False) is True for k in node.keywords):
                required |= names
    return (options | {"--help"}, required) if options else None


def wrong_options(text: str) -> list[str]:
    """Each command line of `named_commands(text)` with an option that its command does not take, or
    without one its script requires (a missing command or file: the tests above)."""
    known = sgr_options()
    wrong = []
    for what, options in named_commands(text):
        if what.startswith("sgr "):
            takes, needs = known.get(what, options), set()
        else:
            parsed = script_options(ROOT / what) if (ROOT / what).exists() else None
            takes, needs = parsed if parsed is not None else (options, set())
            if "--help" in options:
                needs = set()
        wrong += [f"{what} {o}: no such option" for o in sorted(options - takes)]
        wrong += [f"{what} without {o}" for o in sorted(needs - options)]
    return sorted(set(wrong))


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_file_path_a_page_names_exists(page):
    missing = sorted(p for p in named_paths(page.read_text())
                     if not p.startswith("../shared/") and not (ROOT / p).exists() and p not in THE_READERS)
    assert not missing, f"{page.name} names files that do not exist: {missing}"


@pytest.mark.skipif(not SHARED.is_dir(), reason="no shared folder beside this checkout (../shared)")
@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_shared_path_a_page_names_exists(page):
    missing = sorted(p for p in named_paths(page.read_text())
                     if p.startswith("../shared/") and not (ROOT / p).exists())
    assert not missing, f"{page.name} names shared files that do not exist: {missing}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_sgr_command_a_page_names_exists(page):
    from evolve.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "cmd")
    unknown = sorted(sgr_commands(page.read_text()) - set(sub.choices))
    assert not unknown, f"{page.name} names sgr commands that do not exist: {unknown}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_option_a_command_line_names_is_one_its_command_takes(page):
    """`sgr CMD --opt` against the CLI's parser; `python bench/x.py --opt` (and studies/, tools/,
    device/, references/) against the options the script's argparse declares, its required ones
    included, read from its source."""
    wrong = wrong_options(page.read_text())
    assert not wrong, f"{page.name} names command lines that would not run: {wrong}"


def test_the_option_check_can_fail():
    text = ("Run `sgr evolve --frobnicate 3`, `python bench/gpu_probe.py` and\n```\n"
            "python bench/env_host_tasks.py --robots 8 \\\n    --tasks A --nope\n```\n")
    assert wrong_options(text) == ["bench/env_host_tasks.py --nope: no such option",
                                   "bench/gpu_probe.py without --out",
                                   "sgr evolve --frobnicate: no such option"]
    assert not wrong_options("`sgr evolve --task Walker-v0 --debug && python bench/gpu_probe.py --out d`")


def test_the_path_and_command_checks_can_fail():
    text = "Run `python bench/no_such_bench.py` then `sgr frobnicate RUN` (see `docs/BENCHMARKS.md`)."
    assert named_paths(text) == {"bench/no_such_bench.py", "docs/BENCHMARKS.md"}
    assert named_paths("`results/big/runs/sgr-<task>-s<seed>` and `results/big/runs/{name}`") == set()
    assert sgr_commands(text) == {"frobnicate"}


def test_sgr_bench_record_writes_a_record_of_what_it_measured(tmp_path, monkeypatch, capsys):
    from evolve.cli import main

    monkeypatch.setenv("SGR_THREADS", "1")
    assert main(["bench", "--robots", "2", "--steps", "3", "--record", str(tmp_path / "b.json")]) == 0
    record = json.loads((tmp_path / "b.json").read_text())
    assert RECORD_KEYS <= set(record) and record["name"] == "b"
    assert record["command"].endswith("sgr bench --task Walker-v0 --robots 2 --steps 3")
    assert "SGR_THREADS=1 " in record["command"]
    printed = capsys.readouterr().out.splitlines()[-1]  # "... N robot-steps/s (env), M (physics only) ..."
    env, physics = (float(x) for x in re.findall(r"(\d+) (?:robot-steps/s \(env\)|\(physics only\))",
                                                 printed))
    assert figure_values(record, "env") == [env] and figure_values(record, "physics") == [physics]
    assert re.fullmatch(r"[0-9a-f]{12}(\+dirty)?", record["commit"]) and record["machine"]


# every benchmark script that writes a record, at sizes that take a second
BENCH_RECORDS = {
    "host_build_bench.py": ["--sizes", "16", "--old-max", "16", "--step-size", "32", "--steps", "2"],
    "body_size_bench.py": ["--sizes", "3", "--robots", "2", "--steps", "5"],
    "device_state_bench.py": ["--robots", "8", "--steps", "2", "--rounds", "1"],
    "env_host_tasks.py": ["--tasks", "Walker-v0", "--robots", "8", "--steps", "2"],
    "ga_ppo_bench.py": ["--bodies", "2", "--timesteps", "128", "--base-timesteps", "64", "--cores", "1"],
    "generation_bench.py": ["--pop", "4", "--generations", "1", "--workers", "1"],
    "pinning_bench.py": ["--robots", "2", "--steps", "3", "--rounds", "1", "--counts", "1",
                         "--evolve-counts", ""],
    "rl_bench.py": ["--envs", "1", "2", "--timesteps", "256"],
    "rl_learn.py": ["--envs", "2", "--n-steps", "32", "--batch", "32", "--epochs", "1", "--timesteps", "256",
                    "--eval-every", "1"],
}


LONG_BENCHES = ("ga_ppo_bench.py", "pinning_bench.py")  # 13-20 s each: `-m long`


def test_every_bench_script_that_takes_record_is_listed_here():
    takes = {p.name for p in (ROOT / "bench").glob("*.py") if '"--record"' in p.read_text()}
    assert takes == set(BENCH_RECORDS)


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("script", [pytest.param(s, marks=pytest.mark.long) if s in LONG_BENCHES else s
                                    for s in sorted(BENCH_RECORDS)])
def test_a_bench_scripts_record_option_writes_a_record_of_its_figures(script, tmp_path):
    """The commands BENCHMARKS.md cites write their records (one wrote none: a stale key), from any
    folder."""
    import subprocess
    import sys

    out = tmp_path / "r.json"
    run = subprocess.run([sys.executable, str(ROOT / "bench" / script), *BENCH_RECORDS[script],
                          "--record", str(out)], cwd=tmp_path, capture_output=True, text=True,
                         env={**os.environ, "SGR_THREADS": "1"}, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    record = json.loads(out.read_text())
    assert RECORD_KEYS <= set(record) and record["name"] == "r" and record["figures"]
    for key in record["figures"]:
        values = figure_values(record, key)
        assert values and all(isinstance(v, int | float) for v in values), (key, values)



# paths the code names that are not this repository's files, each with why
NOT_OURS = {
    "tests/screen_free/test_baseline_envs.py": "evogym's own test, which tests/sgr/evogym ports",
    "tests/screen_free/test_img_render_modes.py": "evogym's own test, which tests/sgr/evogym ports",
    "tests/screen_free/test_utils.py": "evogym's own test, which tests/sgr/evogym ports",
    "tests/requires_screen/test_screen_render_modes.py": "evogym's own test, which tests/sgr/evogym ports",
    "bench/x.py": "a made-up name in a test or an example", "bench/no_such_bench.py": "a test's missing file",
    "evolve/x.py": "a test's made-up module",
    "tsim/kernels.py": "the stale pointer test_the_code_path_check_can_fail looks for",
    **THE_READERS,
}


def code_paths(text: str) -> set[str]:
    """The repository paths a source file names anywhere (docstrings, comments, strings), as
    `named_paths` reads a page's code spans; examples/ is evogym's (this repository has none)."""
    found = set()
    for m in PATH.finditer(text):
        path = m.group(1)
        if path.startswith(("../shared", "examples/")) or re.match(r"-?[<{]", text[m.end():m.end() + 2]):
            continue
        if not re.search(r"[*<>{}]|\.\.\.|[A-Z]{3,}_?[A-Z]*/|/[A-Z_]{3,}(?:/|$)", path):
            found.add(path.split("::")[0].rstrip("."))
    return found


def test_every_repository_path_the_code_names_exists():
    """No stale pointer in the code: every path of the repository that a docstring, comment or
    string of a .py or .sh file of its folders names is a file or folder here (or in NOT_OURS,
    with why)."""
    folders = ("tsim", "tasks", "parity", "evolve", "sgr", "bench", "tools", "studies", "tests", "references",
               "device")
    sources = [f for d in folders for pattern in ("*.py", "*.sh") for f in (ROOT / d).rglob(pattern)
               if "__pycache__" not in f.parts]
    assert len(sources) > 300
    missing = sorted(f"{p} (in {f.relative_to(ROOT)})" for f in sources for p in code_paths(f.read_text())
                     if not (ROOT / p).exists() and p not in NOT_OURS)
    assert not missing, f"the code names paths that do not exist: {missing}"


def test_the_code_path_check_can_fail():
    named = code_paths("see tsim/kernels.py and evolve/report/qd.py")
    assert named == {"tsim/kernels.py", "evolve/report/qd.py"}
    assert not (ROOT / "tsim/kernels.py").exists()
