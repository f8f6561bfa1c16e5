"""The evolve side of single precision: the run config's `precision` key and controllers that
compute in the observations' real type (float32 observations in an f32 process)."""

import numpy as np
import pytest

from evolve.nn.dense import ControllerBatch, DenseController
from evolve.runs.config import config_from_dict


def test_precision_key_is_checked_and_recorded(monkeypatch):
    monkeypatch.delenv("SGR_PRECISION", raising=False)
    base = {"method": "sgr", "task": "Walker-v0"}
    assert config_from_dict(base).precision == "f64"  # recorded, not null: a resume keeps it
    assert config_from_dict({**base, "precision": "f32"}).precision == "f32"
    monkeypatch.setenv("SGR_PRECISION", "f32")
    assert config_from_dict(base).precision == "f32"  # null: $SGR_PRECISION
    assert config_from_dict({**base, "precision": "f64"}).precision == "f64"  # the key wins
    with pytest.raises(ValueError, match=r"^config: key 'precision': unknown precision 'f16'; use one of "
                                         r"f64, f32$"):
        config_from_dict({**base, "precision": "f16"})


def _controllers(n: int, rng) -> list[DenseController]:
    out = []
    for _ in range(n):
        Ws = [rng.normal(size=(12, 8)), rng.normal(size=(8, 25))]
        bs = [rng.normal(size=8), rng.normal(size=25)]
        out.append(DenseController(Ws, bs, ["tanh", "tanh"], 10, np.array([0, 3, 7, 24])))
    return out


def test_controllers_act_in_the_observations_real_type():
    """float32 observations give float32 actions within float32 rounding of the float64 ones;
    float64 observations give float64 actions equal to the one-robot controller's."""
    rng = np.random.default_rng(0)
    ctrls = _controllers(3, rng)
    obs = rng.normal(size=(3, 12))
    a64 = ControllerBatch(ctrls, 12, 4).act(obs)
    a32 = ControllerBatch(ctrls, 12, 4).act(obs.astype(np.float32))
    assert a64.dtype == np.float64 and a32.dtype == np.float32
    assert np.abs(a32 - a64).max() < 1e-5
    assert 0 < np.abs(a32 - a64).max()  # really computed in float32
    one = ctrls[1].act(obs[1, :10].astype(np.float32))
    assert one.dtype == np.float32
    np.testing.assert_array_equal(ctrls[1].act(obs[1, :10]), a64[1])
