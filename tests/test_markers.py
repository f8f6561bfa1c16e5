"""Each test file marks its own tests (tests/conftest.py says how); these tests check the marks
against what the tests do: the whole tree is collected in this process, and the source a test
runs (its function, the functions of its module it calls, its fixtures) is read for the ways a
test starts another program. A test that starts one and is left out of `slow` would slow the
inner loop (`pytest -m "not slow"`) unseen; a Ray test outside the `ray` group would run beside
another's and lose its actors to that test's `ray stop`."""

import ast
import functools
import inspect
import re
import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# what starting a program looks like in a test's source
STARTS = {
    "subprocess": re.compile(r"\bsubprocess\.(?:run|Popen|call|check_call|check_output)\b|\bsys\.executable\b"
                             r"|[\"']?workers[\"']?\s*[:=]\s*[2-9]"),
    "ray": re.compile(r"\bray\.init\(|\bCluster\(|\bRayRolloutPool\("),
    "browser": re.compile(r"\bplaywright\b|\bchromium\b", re.I),
}

# Tests that start a program yet stay in the fast loop, each for its reason. Moving the marks into
# the test files (issue 46) kept every selection as it was; these are what the check found then.
# The list cannot go stale: each entry must still exist, still start what it says, and stay fast.
FAST_ANYWAY = {
    "tests/test_tree_size.py::test_tree_and_device_wheels_fit_56_mib": "`git ls-files`, not Python",
    "tests/sgr/test_sgr_package.py::test_import_sgr_registers_the_sgr_gymnasium_ids":
        "one `python -c 'import sgr'`: a fresh process is the point (registration on import)",
    "tests/evolve/test_working_folder.py::test_another_tasks_package_first_on_the_path_is_passed_over"
    "_with_one_line": "one short `python -P -c` import: a fresh sys.path is the point",
    "tests/tsim/test_precision.py::test_f32_follows_f64_where_random_robots_touch_walls_and_objects":
        "Taichi starts one precision per process: the f32 side runs in one short process",
    "tests/tsim/test_precision.py::test_f32_pairs_sum_as_float64_does_and_segment_ends_resolve_what"
    "_quotients_cannot": "Taichi starts one precision per process: the f32 side runs in one short process",
    "tests/tsim/backend/test_vulkan.py::test_an_arch_without_its_device_fails_in_one_line":
        "a process that fails at Taichi's start, in about a second",
    "tests/tsim/backend/test_vulkan.py::test_vulkan_without_a_driver_fails_in_one_line":
        "a process that fails at Taichi's start, in about a second",
    "tests/evolve/rollout/test_robust.py::test_accumulated_runs_do_not_depend_on_the_worker_count_and"
    "_their_champion_rescores_exactly": "two rollout workers for a run of a few tiny generations",
    "tests/evolve/rollout/test_robust.py::test_settled_runs_do_not_depend_on_the_worker_count_and_spend"
    "_fewer_episodes": "two rollout workers for a run of a few tiny generations",
}


class _Collector:
    items: list[pytest.Item] = []

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        self.items = list(session.items)


@pytest.fixture(scope="module")
def items() -> list[pytest.Item]:
    """Every test of the tree, collected as `pytest` collects it (marks and groups applied)."""
    collector = _Collector()
    code = pytest.main(["--collect-only", "-q", "-n", "0", "-p", "no:cacheprovider", str(ROOT / "tests")],
                       plugins=[collector])
    assert code == 0, "collecting the tests failed"
    assert len(collector.items) > 500
    return collector.items


@functools.cache
def _source(f: Callable) -> str:
    try:
        return inspect.getsource(f)
    except (OSError, TypeError):
        return ""


@functools.cache
def _calls(f: Callable) -> tuple[Callable, ...]:
    """The functions of `f`'s own module that `f` names."""
    try:
        tree = ast.parse(textwrap.dedent(_source(f)))
    except SyntaxError:
        return ()
    module = inspect.getmodule(f)
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    return tuple(g for n in sorted(names) if inspect.isfunction(g := getattr(module, n, None))
                 and g.__module__ == f.__module__)


def runs_code(item: pytest.Item) -> str:
    """The source `item` runs: its function, the functions of the same module it calls (and those
    call), and its fixtures."""
    todo = [item.function] + [d.func for defs in item._fixtureinfo.name2fixturedefs.values() for d in defs]
    seen: set = set()
    texts = []
    while todo:
        f = inspect.unwrap(todo.pop())
        if f in seen or not inspect.isfunction(f):
            continue
        seen.add(f)
        texts.append(_source(f))
        todo += _calls(f)
    return "\n".join(texts)


def starts(item: pytest.Item) -> set[str]:
    """What programs `item`'s source starts (keys of STARTS)."""
    code = runs_code(item)
    return {kind for kind, pattern in STARTS.items() if pattern.search(code)}


def key(item: pytest.Item) -> str:
    return item.nodeid.split("[")[0]


def test_no_test_in_the_fast_loop_starts_a_program_unless_listed_with_its_reason(items):
    fast = [i for i in items if not i.get_closest_marker("slow")]
    unmarked = sorted({key(i) for i in fast if starts(i)} - set(FAST_ANYWAY))
    assert not unmarked, f"these start programs: mark them slow (and subprocess, ray, browser): {unmarked}"


def test_the_fast_anyway_list_names_fast_tests_that_start_programs(items):
    by_key = {key(i): i for i in items}
    for name in FAST_ANYWAY:
        assert name in by_key, f"{name}: no such test (renamed? then rename it here)"
        assert starts(by_key[name]), f"{name} starts no program now: take it off FAST_ANYWAY"
        assert not by_key[name].get_closest_marker("slow"), f"{name} is slow now: take it off FAST_ANYWAY"


def test_ray_and_browser_tests_carry_their_marker(items):
    for kind in ("ray", "browser"):
        missing = sorted({key(i) for i in items if kind in starts(i) and not i.get_closest_marker(kind)})
        assert not missing, f"these start {kind} without its marker: {missing}"


def test_a_test_that_starts_programs_is_slow_and_ray_tests_share_one_xdist_group(items):
    """Two workers would otherwise run two Ray files at once, and one's `ray stop` kills the
    other's actors; other tests go by file (they share module fixtures, some run in order)."""
    ray = [i for i in items if i.get_closest_marker("ray")]
    assert len({i.path for i in ray}) >= 2
    for item in items:
        if any(item.get_closest_marker(m) for m in ("subprocess", "ray", "browser", "vulkan")):
            assert item.get_closest_marker("slow"), item.nodeid
        group = item.get_closest_marker("xdist_group").args[0]
        rel = Path(str(item.path)).resolve().relative_to(ROOT).as_posix()
        assert group == ("ray" if item in ray else rel), (item.nodeid, group)
