"""No file sgr reads can run code: nothing in the packages unpickles except the worker pipes of one
run's own processes (evolve/rollout/pool.py, worker.py) and the conversion of an older sgr's
pickles (checkpoints, a script's task.pkl) that the user must ask for with --trust-pickle
(evolve/records/legacy.py); every np.load says allow_pickle=False; YAML is read with safe_load only;
nothing evals, execs or imports a name at run time, except the task modules a config names
(tasks/registry.py: from a run or sweep folder only after --trust-imports). Checked on the
source's syntax tree."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("tsim", "tasks", "parity", "evolve")
# a run folder keeps a script's task as a reference (task.json), never as a pickle: tasks/registry.py
# unpickles nothing (tests/evolve/runs/test_folder_trust.py)
MAY_UNPICKLE = {"evolve/rollout/pool.py", "evolve/rollout/worker.py", "evolve/records/legacy.py"}
# imports the task modules a config names (`imports:`) and the file a task reference names: from a
# run or sweep folder only with --trust-imports (tests/evolve/runs/test_folder_trust.py)
MAY_IMPORT_BY_NAME = {"tasks/registry.py"}
# trains with torch (method ga-ppo); calls no torch.load, torch.jit.load (checked below): nothing read
MAY_IMPORT_TORCH = {"evolve/rollout/ppo.py"}
CODE_LOADERS = {"pickle", "cPickle", "_pickle", "dill", "cloudpickle", "marshal", "shelve", "joblib", "torch"}


def problems(source: str, rel: str) -> list[str]:
    """Every place in `source` (the file `rel`) that could load code from a file."""
    out = []
    for node in ast.walk(ast.parse(source)):
        where = f"{rel}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Import | ast.ImportFrom):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            for name in names:
                torch_ok = name.split(".")[0] == "torch" and rel in MAY_IMPORT_TORCH
                if name.split(".")[0] in CODE_LOADERS and rel not in MAY_UNPICKLE and not torch_ok:
                    out.append(f"{where}: imports {name}")
        elif isinstance(node, ast.Call):
            f = node.func
            dotted = ast.unparse(f)
            if dotted in ("np.load", "numpy.load"):
                kw = {k.arg: k.value for k in node.keywords}
                flag = kw.get("allow_pickle")
                if not (isinstance(flag, ast.Constant) and flag.value is False):
                    out.append(f"{where}: {dotted} without allow_pickle=False")
            elif dotted in ("yaml.load", "yaml.unsafe_load", "yaml.full_load", "yaml.load_all"):
                out.append(f"{where}: {dotted} (only yaml.safe_load)")
            elif dotted in ("torch.load", "torch.jit.load", "th.load"):
                out.append(f"{where}: {dotted}")
            elif dotted in ("eval", "exec", "__import__"):
                out.append(f"{where}: {dotted}")
            elif dotted in ("importlib.import_module", "import_module") and rel not in MAY_IMPORT_BY_NAME:
                out.append(f"{where}: {dotted}")
    return out


def test_the_check_finds_each_kind_of_loader():
    """The control: each way of loading code is reported (so the test below can fail)."""
    src = ("import pickle\nimport numpy as np\nimport yaml\nimport importlib\n"
           "np.load(f)\nnp.load(f, allow_pickle=True)\nyaml.load(s)\neval(s)\nimportlib.import_module(s)\n"
           "np.load(f, allow_pickle=False)\nyaml.safe_load(s)\ntorch.load(f)\n")
    found = problems(src, "evolve/x.py")
    assert [p.split(": ", 1)[1] for p in found] == [
        "imports pickle", "np.load without allow_pickle=False", "np.load without allow_pickle=False",
        "yaml.load (only yaml.safe_load)", "eval", "importlib.import_module", "torch.load"]
    assert problems("import pickle\n", "evolve/rollout/worker.py") == []


def test_no_module_of_the_packages_loads_code_from_a_file():
    files = [f for p in PACKAGES for f in sorted((ROOT / p).rglob("*.py"))]
    assert len(files) > 40
    found = [p for f in files for p in problems(f.read_text(), f.relative_to(ROOT).as_posix())]
    assert found == []


def test_tests_and_benches_read_arrays_without_pickle():
    """Reference data in tests/data and the benches' inputs are read with allow_pickle=False too."""
    files = [f for d in ("tests", "bench", "references", "studies", "device", "tools")
             for f in sorted((ROOT / d).rglob("*.py"))]
    found = [p for f in files for p in problems(f.read_text(), f.relative_to(ROOT).as_posix())
             if "np.load" in p or "numpy.load" in p]
    assert found == []
