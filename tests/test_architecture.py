"""The layers: no import cycle among the project's modules (module-level or inside functions), and
each layer imports only the layers above it (tsim <- tasks <- parity <- evolve <- sgr: parity is
the evogym comparison harness; sgr, the face users import, sits on top and nothing imports it)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("tsim", "tasks", "parity", "evolve", "sgr")
LAYER = {"tsim": 0, "tasks": 1, "parity": 2, "evolve": 3, "sgr": 4}


def modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for f in (ROOT / pkg).rglob("*.py"):
            parts = f.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f
    return out


def imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Project modules `name` imports anywhere in its file; `from pkg import sub` counts as pkg.sub
    when sub is a module."""
    out = set()
    is_pkg = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import
                base = name.split(".")[: len(name.split(".")) - node.level + (1 if is_pkg else 0)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                out.add(f"{mod}.{a.name}" if f"{mod}.{a.name}" in known else mod)
    return {m for m in out if m in known and m != name}


def graph() -> dict[str, set[str]]:
    mods = modules()
    return {m: imports(m, p, set(mods)) for m, p in mods.items()}


def find_cycle(g: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for n in sorted(g[m]):
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state and (c := visit(n)):
                return c
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(g):
        if m not in state and (c := visit(m)):
            return c
    return None


def test_no_import_cycle():
    g = graph()
    assert len(g) > 30  # the walk found the project
    assert find_cycle(g) is None, " -> ".join(find_cycle(g))


def test_the_cycle_finder_finds_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_each_layer_imports_only_the_layers_above_it():
    bad = [f"{m} imports {n}" for m, deps in graph().items() for n in deps
           if LAYER[n.split(".")[0]] > LAYER[m.split(".")[0]]]
    assert not bad, bad


def test_nothing_below_sgr_imports_it():
    """sgr (and sgr.evogym) is the top layer: tsim, tasks and evolve never import it."""
    g = graph()
    assert any(m.startswith("sgr.evogym") for m in g)  # the walk found the package
    bad = [f"{m} imports {n}" for m, deps in g.items() for n in deps
           if n.split(".")[0] == "sgr" and m.split(".")[0] != "sgr"]
    assert not bad, bad


# tsim is physics first: its backend subpackage (tsim/backend/: the Backend seam, Taichi's start-up,
# devices, launchers, host/device arrays) is reached only from the simulator and its kernels, so
# that bodies, worlds, layouts, rendering and files stay numpy that any layer may use without Taichi.
BACKEND_USERS = ("tsim.sim", "tsim.kernels")


def test_only_the_simulator_and_its_kernels_import_tsim_backend():
    g = graph()
    assert "tsim.backend.runtime" in g and "tsim.layout" in g  # the walk found both sides
    bad = [f"{m} imports {n}" for m, deps in g.items() if m.startswith("tsim.")
           and not m.startswith(("tsim.backend",) + BACKEND_USERS) for n in deps
           if n == "tsim.backend" or n.startswith("tsim.backend.")]
    assert not bad, bad


# Inside evolve/, each layer imports only its own and the layers before it, lazy (in-function)
# imports included (the walk reads whole files). The order, from the code: own_modules (what the
# worker processes may import) < nn (the networks, and a genome as a JSON record, from which they
# are compiled) < search (NEAT's search and MAP-Elites', their checkpoint state) < rollout
# (episodes, worker pools, robust evaluation's noise) < config (the RunConfig: it parses `robust`
# with the rollout's Robust) < methods (they read the config and simulate through the rollout) <
# records (what a run leaves on disk: the run folder, champion.json and its replays, the verdict,
# segments, decoding, older formats) < report (reads those records; a run draws its own
# fitness.png with it) < runs (a run's lifecycle, which writes the records; `sgr migrate` is here:
# it restores old pickles into an Experiment) < sweeps (many runs) < cli < the evolve package's
# face (evolve/__init__.py).
EVOLVE_LAYERS = ("evolve.own_modules", "evolve.nn", "evolve.search", "evolve.rollout", "evolve.config",
                 "evolve.methods", "evolve.records", "evolve.report", "evolve.runs", "evolve.sweeps",
                 "evolve.cli", "evolve")


def evolve_layer(module: str) -> int | None:
    """The index in EVOLVE_LAYERS of the (deepest) layer `module` belongs to; None outside evolve."""
    found = None
    for i, layer in enumerate(EVOLVE_LAYERS):
        for name in layer if isinstance(layer, tuple) else (layer,):
            if module == name or module.startswith(name + ".") and name != "evolve":
                found = i
    return found if found is not None or module != "evolve" else len(EVOLVE_LAYERS) - 1


def upward_imports(g: dict[str, set[str]]) -> list[str]:
    """Every import inside evolve/ of a later layer than the importer's."""
    def later(m: str, n: str) -> bool:
        lm, ln = evolve_layer(m), evolve_layer(n)
        return lm is not None and ln is not None and ln > lm

    return [f"{m} imports {n}" for m, deps in g.items() for n in deps if later(m, n)]


def test_inside_evolve_no_layer_imports_a_later_one():
    """The config sits below the methods: no method imports the run's lifecycle (evolve.runs) to
    read its config, not even inside a function."""
    g = graph()
    unplaced = [m for m in g if m.startswith("evolve") and evolve_layer(m) is None]
    assert not unplaced, f"place these modules in EVOLVE_LAYERS: {unplaced}"
    assert not upward_imports(g), upward_imports(g)


def test_the_layer_walk_finds_an_upward_import():
    """The check can fail: a method importing evolve.runs (as methods/base.py once did, lazily)."""
    assert upward_imports({"evolve.methods.base": {"evolve.runs.run_config"}}) == \
        ["evolve.methods.base imports evolve.runs.run_config"]
    assert upward_imports({"evolve.runs.experiment": {"evolve.config", "evolve.methods"}}) == []
    assert evolve_layer("evolve") == len(EVOLVE_LAYERS) - 1 and evolve_layer("evolve.nn.cppn") == 1


# A run config is read by attribute (`cfg.task`), never as a mapping, outside evolve/config.py. The
# rule: no subscript and no `.get(` on a name (or attribute) called cfg, config, run_cfg, run_config
# or conf, nor on the result of a call that makes a RunConfig (load_config(...)["task"]); a raw YAML
# mapping (a config.yaml read for a report) is named otherwise (`raw`).
CONFIG_NAMES = {"cfg", "config", "run_cfg", "run_config", "conf"}
CONFIG_MAKERS = {"load_config", "config_from_dict", "check_config", "of", "build", "replace"}


def mapping_reads(source: str) -> list[str]:
    """`cfg[...]` and `cfg.get(...)` on a config name in Python source, as (line: code)."""
    def named(n: ast.AST) -> bool:
        if isinstance(n, ast.Call):
            f = n.func
            return (isinstance(f, ast.Name) and f.id in CONFIG_MAKERS
                    or isinstance(f, ast.Attribute) and f.attr in CONFIG_MAKERS and (
                        f.attr != "replace" or named(f.value)))
        return (isinstance(n, ast.Name) and n.id in CONFIG_NAMES
                or isinstance(n, ast.Attribute) and n.attr in CONFIG_NAMES)

    out = []
    for n in ast.walk(ast.parse(source)):
        if isinstance(n, ast.Subscript) and named(n.value) or (
                isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute) and n.func.attr == "get"
                and named(n.func.value)):
            out.append(f"{n.lineno}: {ast.unparse(n)[:60]}")
    return out


def test_the_run_config_is_read_by_attribute_everywhere():
    files = [f for d in ("evolve", "tasks", "tsim", "sgr", "bench", "references", "studies", "device",
                                 "tools", "tests")
             for f in (ROOT / d).rglob("*.py") if f != ROOT / "evolve" / "config.py"]
    assert len(files) > 100
    bad = [f"{f.relative_to(ROOT)}:{hit}" for f in files for hit in mapping_reads(f.read_text())]
    assert not bad, bad


def test_the_mapping_read_scan_finds_subscripts_and_get():
    src = ('a = cfg["task"]\nb = self.cfg.get("seed")\nc = exp.cfg.task\nd = raw["task"]\nconfig[k] = 1\n'
           'e = load_config(p)["seed"]\nf = RunConfig.of(raw).get("x")\ng = s.replace("a", "b")[0]\n')
    assert [hit.split(":")[0] for hit in mapping_reads(src)] == ["1", "2", "5", "6", "7"]
