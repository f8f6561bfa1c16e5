from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return Path(__file__).resolve().parents[1]


# ------------------------------------------------------------------ markers (pyproject.toml lists them)
# Each test file marks its own tests (a module-level `pytestmark = [...]` or a decorator): tests
# that start other programs carry what they start: `subprocess` (python processes: the CLI,
# rollout workers, pip), `ray` (a Ray instance or cluster), `browser` (headless Chromium), `vulkan`
# (a Vulkan device or lavapipe); each of these is `slow` too (added here if the file left it out).
# `slow` alone marks in-process tests that simulate long. `pytest -m "not slow"` is the inner
# loop; `pytest` runs everything but `long` (a long scenario beside a shorter test of the same fact,
# also `slow`: pyproject's addopts leave it out, so the suite stays under 10 minutes on 2 cores);
# `pytest -m long` runs those. tests/test_markers.py checks the marks against what tests do.
STARTS_PROGRAMS = ("subprocess", "ray", "browser", "vulkan")


def xdist_group(rel: str, marks: set[str]) -> str:
    """The group of tests one pytest-xdist worker runs in order (`--dist loadgroup`, pyproject's
    addopts): a test file's tests together (they share module fixtures and some run in order),
    and every test that starts Ray in one group, since stopping a Ray instance stops the
    machine's others (a test's actors died beside another file's in a two-worker trial)."""
    return "ray" if "ray" in marks else rel


def pytest_collection_modifyitems(config, items) -> None:
    """A test that starts programs is slow; each test's xdist group, from its own markers."""
    root = Path(__file__).resolve().parents[1]
    for item in items:
        marks = {m.name for m in item.iter_markers()}
        if (marks & set(STARTS_PROGRAMS) or "long" in marks) and "slow" not in marks:
            item.add_marker(pytest.mark.slow)
        rel = Path(str(item.path)).resolve().relative_to(root).as_posix()
        item.add_marker(pytest.mark.xdist_group(xdist_group(rel, marks)))


@pytest.fixture(autouse=True)
def _task_registry_as_found():
    """Tasks registered and trust given in this process by one test (a script's `register`, an
    in-process `main([..., "--trust-imports"])`) are gone after it: the tests a worker runs next
    see sgr's own tasks and no trust, whatever ran before them on that worker."""
    import sys

    yield
    registry = sys.modules.get("tasks.registry")
    if registry is None:
        return
    import gymnasium as gym

    from tasks.specs import BUILTIN, TASKS, forget_worlds

    registry.trust_imports(False)
    extra = [name for name in TASKS if name not in BUILTIN]
    for name in extra:
        del TASKS[name]
        gym.registry.pop(f"sgr/{name}", None)
    if extra:
        forget_worlds()
