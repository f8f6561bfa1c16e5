"""Body topology: evogym's point order, exact initial positions, springs and actuator order."""

import json
import re

import numpy as np
import pytest

from tasks.specs import task_world
from tsim import constants as C
from tsim.body import BL, BR, TL, TR, build_body, check_robot, full_connectivity, is_connected


def _cases(data_dir):
    index = json.loads((data_dir / "traces" / "index.json").read_text())
    return [np.load(data_dir / "traces" / c["file"], allow_pickle=False) for c in index["cases"]]


def test_point_order_and_positions_match_evogym_traces(data_dir):
    for z in _cases(data_dir):
        b = build_body(z["body"])
        assert b.n_points == z["robot_pos0"].shape[1]
        # bit-identical initial doubles: reset contacts depend on their 1e-17 rounding
        assert np.array_equal(b.place(*z["robot_origin_cell"]), z["robot_pos0"])
        for v, (r, c) in enumerate(b.voxel_rc):
            p = b.voxel_points[v]
            assert list(z["corner_points"][r, c]) == [p[TL], p[TR], p[BL], p[BR]]
        assert list(b.actuator_flat) == list(z["actuator_voxel_index"])


def test_world_objects_match_evogym_global_points(data_dir):
    for z in _cases(data_dir):
        world = task_world(str(z["task"]))
        for o in json.loads(str(z["world_objects"])):
            if o["name"] == "robot":
                continue
            ref = z["world_pos0"][:, o["first_point"]:o["first_point"] + o["n_points"]]
            assert np.array_equal(world.object(o["name"]).pos0, ref)


def test_spec_point_counts_and_order():
    b = build_body(np.full((3, 3), C.RIGID))
    assert b.n_points == 16
    pos = b.place(1, 1)
    assert np.allclose(pos[:, 4], [0.3, 0.4]) and np.allclose(pos[:, 8], [0.1, 0.2])
    assert build_body([[1, 0, 1], [3, 3, 3], [0, 4, 0]]).n_points == 14
    assert build_body(np.full((5, 5), C.SOFT)).n_points == 36


def test_shared_edge_stiffness_last_non_rigid_owner_wins():
    b = build_body([[3], [2]])  # actuator above soft: shared edge gets the soft constant
    shared = b.voxel_edges[0, 2]
    assert shared == b.voxel_edges[1, 0]
    assert b.edge_k[shared] == C.K_SOFT_MAIN
    b = build_body([[2], [3]])
    assert b.edge_k[b.voxel_edges[0, 2]] == C.K_ACT_MAIN
    b = build_body([[1, 1]])
    assert b.edge_k[b.voxel_edges[0, 1]] == C.K_RIGID_MAIN
    b = build_body([[1, 2]])
    assert b.edge_k[b.voxel_edges[0, 1]] == C.K_SOFT_MAIN
    assert b.n_edges == 7 + 4  # 7 main edges (one shared) + 2 diagonals per voxel


def test_stacked_actuators_share_their_driven_edge():
    b = build_body([[3], [3]])
    shared = b.voxel_edges[0, 2]
    assert sorted(b.edge_drivers[shared]) == [0, 1]
    b = build_body([[4, 4]])
    assert sorted(b.edge_drivers[b.voxel_edges[0, 1]]) == [0, 1]
    assert b.edge_drivers[b.voxel_edges[0, 0]][1] == -1  # top of a V voxel is not driven


def test_connectivity_helpers():
    assert is_connected([[1, 1], [0, 1]])
    assert not is_connected([[1, 0], [0, 1]])
    assert not is_connected([[0, 0]])
    assert full_connectivity([[1, 1], [0, 1]]).tolist() == [[0, 1], [1, 3]]


@pytest.mark.parametrize("matrix, words", [
    ([1, 2, 3], "2-D"),
    ([[1, 7]], "0-4"),
    ([[-1, 3]], "0-4"),
    ([[0, 0], [0, 0]], "empty"),
    (np.zeros((0, 3)), "empty"),
    ([[3, 0], [0, 3]], "connected"),
    ([[1, 2], [2, 1]], "actuator"),
    ([[1.5, 3]], "integers"),
])
def test_bad_bodies_raise_value_error_naming_the_problem(matrix, words):
    with pytest.raises(ValueError, match=words):
        check_robot(matrix)


@pytest.mark.parametrize("connections, words", [
    ("pairs", "got shape (3, 2)"),                 # (k, 2): was re-paired into a body of 14 points
    (np.zeros((3, 4), int), "got shape (3, 4)"),   # was read as 6 pairs
    (np.array([[0.0, 1.5, 2.0], [1.0, 2.0, 3.0]]), "values such as 1.5"),  # was truncated
    (np.array([[0.0, 1.0, 2.0], [1.0, 2.0, np.inf]]), "values such as inf"),  # the pair was dropped
    (np.array([[0, 1, 2], [1, 2, None]], dtype=object), "values such as None"),
])
def test_connections_not_in_evogyms_2_by_k_layout_are_refused(connections, words):
    """build_body and sgr.evogym's WorldObject take evogym's (2, k) connections and nothing they
    would have to reinterpret; (2, k) itself builds the body its full connectivity builds."""
    from sgr.evogym import WorldObject

    m = np.array([[3, 3, 3, 3]])
    full = full_connectivity(m)
    if isinstance(connections, str):
        connections = full.T
    for build in (lambda c: build_body(m, c), lambda c: WorldObject.from_array("r", m, c)):
        with pytest.raises(ValueError, match=re.escape(words)):
            build(connections)
    assert build_body(m, full).n_points == build_body(m).n_points == 10
    assert build_body(m, full.astype(float)).n_points == 10
    assert build_body(m, full.astype(object)).n_points == 10  # Python ints, as a list of lists gives
    assert build_body(m, np.zeros((2, 0), int)).n_points == 16  # nothing glued: four loose voxels


@pytest.mark.parametrize("shape", [(3,), (2, 2, 2)])
def test_is_connected_of_a_matrix_that_is_not_2_d_says_so(shape):
    with pytest.raises(ValueError, match=re.escape(f"needs a 2-D matrix, got shape {shape}")):
        is_connected(np.ones(shape))

