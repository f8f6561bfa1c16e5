"""EvoWorld / WorldObject edits print and raise what evogym's do (tests/data/evogym_api/
world_ops.txt, evogym's output for the same calls, recorded by references/evogym_api_reference.py)."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import sgr.evogym as evogym
from sgr.evogym import EvoWorld, WorldObject

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "tests" / "data" / "evogym_api"


def _reference_script():
    spec = importlib.util.spec_from_file_location("evogym_api_reference",
                                                  ROOT / "references" / "evogym_api_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_world_edits_print_and_fail_as_evogyms():
    assert _reference_script().world_ops(evogym) == (DATA / "world_ops.txt").read_text()


def test_object_round_trips_structure_and_connections():
    body = np.array([[1, 3, 0], [2, 4, 2]])
    conn = np.array([[0, 1, 3, 4], [1, 4, 4, 5]])  # 1-4 vertical, others horizontal; 3-0 missing
    obj = WorldObject.from_array("r", body, conn)
    np.testing.assert_array_equal(obj.get_structure(), body)
    got = {tuple(sorted(p)) for p in obj.get_connections().T.tolist()}
    assert got == {(0, 1), (1, 4), (3, 4), (4, 5)}
    obj.set_pos(4, 2)
    obj.rename("q")
    assert obj.get_pos() == (4, 2) and obj.get_name() == "q"


def test_json_object_loads_one_object_and_rejects_several(tmp_path):
    with pytest.raises(ValueError, match="more than one object"):
        WorldObject.from_json(str(DATA / "simple_environment.json"))
    w = EvoWorld.from_json(str(DATA / "simple_environment.json"))
    assert sorted(w.objects) == ["box", "ground"]
    assert w.objects["box"].get_pos() == (4, 7)  # indices 144-146, 164-166 on a 20-wide grid


def test_connections_naming_an_empty_cell_are_rejected():
    with pytest.raises(ValueError, match="invalid elements"):
        WorldObject.from_array("r", np.array([[1, 0]]), np.array([[0], [1]]))
