"""Body measures (evolve/methods/body_measures.py) on bodies whose measures are known by hand."""

import numpy as np
import pytest

from evolve.methods.body_measures import (
    NAMES,
    boundaries,
    bounding_box,
    describe,
    irregularity,
    measures,
    symmetry_lr,
    symmetry_tb,
)

# a mirror-symmetric (left-right) walker: legs of vertical actuators, a rigid top
ARCH = np.array([[1, 1, 1],
                 [4, 0, 4],
                 [4, 0, 4]])


def test_bounding_box_drops_empty_rows_and_columns():
    """A body drawn in a corner of a 5x5 grid measures as the same body on its own."""
    grid = np.zeros((5, 5), dtype=int)
    grid[2:5, 1:4] = ARCH
    assert np.array_equal(bounding_box(grid), ARCH)
    assert measures(grid) == measures(ARCH)


def test_mirror_symmetric_body_scores_one_left_right_and_less_top_bottom():
    """ARCH is its own left-right mirror. Top to bottom, by hand: row 0 (1 1 1) meets row 2 (4 0 4),
    3 cells filled in either and none agree, twice; row 1 meets itself, 2 filled and 2 agree:
    2 of 8."""
    assert symmetry_lr(ARCH) == 1.0
    assert symmetry_tb(ARCH) == pytest.approx(2 / 8)


def test_asymmetric_body_scores_below_one():
    """An L of one material: left-right, the column of 3 meets the empty cells of its mirror."""
    ell = np.array([[2, 0], [2, 0], [2, 2]])
    # filled in either: rows 0 and 1 both cells (2 each), row 2 both -> 6; agree: row 2 only -> 2
    assert symmetry_lr(ell) == pytest.approx(2 / 6)


def test_uniform_block_is_regular_and_patchwork_is_not():
    """A block of one material compresses like an empty grid (irregularity 0, no boundaries); a
    checkerboard of four materials needs more bytes and every neighbouring pair differs."""
    block = np.full((5, 5), 2)
    checker = np.indices((5, 5)).sum(axis=0) % 2 * 2 + 1  # rigid and horizontal actuators
    patch = np.array([[1, 2, 3, 4, 1], [3, 4, 1, 2, 3], [1, 2, 3, 4, 1], [3, 4, 1, 2, 3], [2, 1, 4, 3, 2]])
    assert irregularity(block) == 0 and boundaries(block) == 0.0
    assert boundaries(checker) == 1.0
    assert irregularity(patch) > irregularity(checker) > 0


def test_material_shares_and_size():
    """ARCH: 7 voxels, 3 rigid and 4 vertical actuators, a 3 x 3 box."""
    m = measures(ARCH)
    assert list(m) == list(NAMES)
    assert (m["width"], m["height"], m["voxels"]) == (3, 3, 7)
    assert m["fill"] == pytest.approx(7 / 9)
    assert (m["rigid"], m["soft"], m["h_actuator"]) == (pytest.approx(3 / 7), 0.0, 0.0)
    assert m["v_actuator"] == m["actuator"] == pytest.approx(4 / 7)


def test_empty_body_is_refused():
    """An empty grid has no body to measure."""
    with pytest.raises(ValueError, match="empty body"):
        measures(np.zeros((5, 5), dtype=int))


def test_describe_gives_rows_x_columns_symmetries_and_the_actuator_share():
    """ARCH: 3x3, left-right 1, top-bottom 2 of 8, 4 of its 7 voxels actuators (57 %); an L of 3
    rows and 2 columns, soft only: "3x2" (rows first, as --shape writes a shape), no actuators."""
    m = measures(ARCH)
    assert describe(m) == (f"3x3, symmetry lr 1.00 tb 0.25, irregularity {m['irregularity']}, "
                           "actuators 57 %")
    ell = measures(np.array([[2, 0], [2, 0], [2, 2]]))
    assert describe(ell).startswith("3x2, symmetry lr 0.33 ") and describe(ell).endswith("actuators 0 %")
