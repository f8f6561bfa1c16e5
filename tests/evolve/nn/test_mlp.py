"""MLP controllers (evolve/nn/mlp.py): a robot's actions are the same bits alone and in any batch,
they match the slow, obvious forward pass, and the JSON form reads back as the same controller."""

from __future__ import annotations

import numpy as np
import pytest

from evolve.nn.mlp import MlpBatch, MlpController


def random_controller(rng: np.random.Generator, obs: int, actions: int, hidden=(64, 64)) -> MlpController:
    sizes = [obs, *hidden, actions]
    return MlpController([rng.normal(0, 0.5, (a, b)).astype(np.float32).astype(np.float64)
                          for a, b in zip(sizes, sizes[1:], strict=False)],
                         [rng.normal(0, 0.5, b) for b in sizes[1:]], obs, actions)


def test_a_robots_actions_are_the_same_bits_alone_and_in_a_padded_batch():
    """Robots of other observation and actuator counts beside it (zero padding) change no bit of
    its actions; every action lies in evogym's range and matches the plain forward pass."""
    rng = np.random.default_rng(0)
    sizes = [(58, 9), (74, 14), (40, 3), (66, 20)]
    ctrls = [random_controller(rng, o, a) for o, a in sizes]
    width, acts = max(o for o, _ in sizes) + 5, max(a for _, a in sizes) + 2
    obs = np.zeros((len(ctrls), width))
    for i, (o, _) in enumerate(sizes):
        obs[i, :o] = rng.normal(0, 1, o)
    out = MlpBatch(ctrls, width, acts).act(obs)
    for i, (c, (o, a)) in enumerate(zip(ctrls, sizes, strict=True)):
        alone = c.act(obs[i, :o])
        assert np.array_equal(out[i, :a], alone)
        np.testing.assert_allclose(alone, c.reference_act(obs[i, :o]), rtol=0, atol=1e-12)
        assert alone.min() >= 0.6 and alone.max() <= 1.6
    assert np.ptp(out[:, 0]) > 0  # the check can fail: the robots act differently


def test_json_reads_back_the_same_controller():
    c = random_controller(np.random.default_rng(1), 30, 6, hidden=(8,))
    again = MlpController.from_json(c.to_json())
    x = np.linspace(-1, 1, 30)
    assert np.array_equal(again.act(x), c.act(x))
    assert all(np.array_equal(a, b) for a, b in zip(again.weights, c.weights, strict=True))


@pytest.mark.parametrize(("change", "match"), [
    (lambda d: d.update(input_size=31), "inputs"),
    (lambda d: d["layers"][0]["biases"].pop(), "do not fit"),
    (lambda d: d.update(n_actions=0), "positive ints"),
    (lambda d: d["layers"][1]["weights"][0].__setitem__(0, float("nan")), "finite"),
])
def test_a_controller_that_does_not_fit_is_refused(change, match):
    d = random_controller(np.random.default_rng(2), 30, 6, hidden=(8,)).to_json()
    change(d)
    with pytest.raises(ValueError, match=match):
        MlpController.from_json(d)
