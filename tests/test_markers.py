"""The marker table (tests/conftest.py MARKS) names real tests: a renamed test or file would
otherwise silently leave the `not slow` loop slower (or a slow test unmarked)."""

import ast
from pathlib import Path

from tests.conftest import MARKS, marks_of, xdist_group

ROOT = Path(__file__).resolve().parents[1]


def test_every_entry_of_the_marker_table_names_an_existing_file_and_its_tests():
    for mark, files in MARKS.items():
        for where, names in files.items():
            path = ROOT / where
            assert path.exists(), (mark, where)
            if names:
                defined = {n.name for n in ast.walk(ast.parse(path.read_text()))
                           if isinstance(n, ast.FunctionDef)}
                assert set(names) <= defined, (mark, where, set(names) - defined)


def test_a_test_that_starts_programs_is_slow():
    assert marks_of("tests/evolve/runs/test_ray_nodes.py", "anything") == {"ray", "subprocess", "slow"}
    assert marks_of("tests/sgr/evogym/requires_screen/test_screen_render_modes_port.py", "t") == {
        "subprocess", "slow"}
    assert marks_of("tests/evolve/runs/test_resume.py", "test_damaged_newest_checkpoint_falls_back_to_the"
                    "_previous_one") == set()


def test_every_ray_test_shares_one_xdist_group_and_other_tests_go_by_file():
    """Two workers would otherwise run two Ray files at once, and one's `ray stop` kills the
    other's actors."""
    ray_tests = [(f, names[0] if names else "any") for f, names in MARKS["ray"].items()]
    assert len(ray_tests) >= 2
    assert {xdist_group(f, marks_of(f, name)) for f, name in ray_tests} == {"ray"}
    assert xdist_group("tests/tsim/test_kernels.py", marks_of("tests/tsim/test_kernels.py", "t")) == (
        "tests/tsim/test_kernels.py")
