"""SGR decoding: one genome -> body (argmax of 5 material outputs per cell) + dense controller."""

import numpy as np

from evolve.methods.sgr.decoder import DecoderSettings, body_from_cppn, decode, is_valid_robot
from evolve.methods.sgr.substrates import cell_coordinates, controller_side
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.dense import ControllerBatch, DenseController
from tasks.env import obs_dim
from tsim.body import build_body


def test_body_is_the_argmax_of_the_body_network_on_each_cell(neat_config, genomes):
    cfg = neat_config()
    s = DecoderSettings()
    for g in genomes(cfg, 8):
        cppn = CompiledCPPN(g, cfg.genome_config)
        body = body_from_cppn(cppn, s)
        # slow oracle: query every weight one at a time
        def w(src, dst, cppn=cppn):
            v = cppn(np.array([[*src, *dst, 1.0]]))[0, 0]
            return 0.0 if abs(v) <= 0.2 else np.sign(v) * (abs(v) - 0.2) / 0.8
        ins = [(-1, 0, 1), (1, 0, 1)]
        hid = [(-1, 0, 2), (0, 0, 2), (1, 0, 2)]
        outs = [(x, 0, 3) for x in (-1, -0.5, 0, 0.5, 1)]
        for (r, c), (x, y) in zip(np.ndindex(5, 5), cell_coordinates((5, 5)), strict=True):
            h = [np.tanh(x * w(ins[0], hn) + y * w(ins[1], hn) + w((0, 0, 0), hn)) for hn in hid]
            o = [sum(h[j] * w(hid[j], on) for j in range(3)) + w((0, 0, 0), on) for on in outs]
            assert body[r, c] == int(np.argmax(o))


def test_validity_rule_needs_a_connected_body_with_an_actuator():
    """The paper's rule: non-empty, 4-connected (diagonal contact does not count), >= 1 actuator."""
    assert is_valid_robot(np.array([[3, 0], [1, 1]])) and is_valid_robot(np.array([[0, 4]]))
    assert not is_valid_robot(np.zeros((5, 5), dtype=np.int64))
    assert not is_valid_robot(np.array([[3, 0], [0, 1]]))  # touching only diagonally
    assert not is_valid_robot(np.array([[3, 3, 0, 4]]))  # two pieces
    assert not is_valid_robot(np.array([[1, 2], [2, 1]]))  # no actuator


def test_controller_matches_the_decoded_body(neat_config, genomes):
    """A seeded population mixes valid and invalid bodies (8 of 16 valid when written; at least 4
    asserted), invalid ones get no controller, and each valid one a controller sized for its
    observation and driving exactly its actuators."""
    cfg = neat_config()
    n_valid = 0
    for g in genomes(cfg, 16):
        p = decode(g, cfg.genome_config, "Climber-v2", DecoderSettings())
        assert p.valid == is_valid_robot(p.body)
        if not p.valid:
            assert p.controller is None
            continue
        n_valid += 1
        b = build_body(p.body)
        n = obs_dim("Climber-v2", b.n_points)
        k = controller_side(n)
        c = p.controller
        assert c.input_size == n and c.weights[0].shape == (k * k, 25) and c.weights[1].shape == (25, 25)
        assert np.array_equal(c.action_cells, b.actuator_flat)
    assert 4 <= n_valid < 16


def test_one_output_feeds_both_networks_two_outputs_split_them(neat_config, genomes):
    """With two CPPN outputs the controller reads output 1 only (cut to zero: no weights), with one
    output it reads the body's output 0 (non-zero weights); the body reads output 0 in both."""
    cfg2 = neat_config(outputs=2)
    gc = cfg2.genome_config
    g = genomes(cfg2, 1, mutations=0, seed=3)[0]  # seed 3 decodes to a valid 4-voxel L-shaped body
    for key in list(g.connections):
        if key[1] == 1:  # cut every link into output 1 (the controller's) and zero its bias
            del g.connections[key]
    g.nodes[1].bias = 0.0
    two = decode(g, gc, "Walker-v0", DecoderSettings(cppn_outputs=2))
    one = decode(g, gc, "Walker-v0", DecoderSettings(cppn_outputs=1))
    assert np.array_equal(two.body, one.body)  # the body reads output 0 in both wirings
    assert two.valid and one.valid
    assert all(np.all(W == 0) for W in two.controller.weights)  # output 1 is 0 -> no links
    assert any(np.any(W != 0) for W in one.controller.weights)


def test_batched_controllers_equal_the_per_robot_forward_pass(neat_config, genomes):
    cfg = neat_config()
    ps = [p for p in (decode(g, cfg.genome_config, "Walker-v0", DecoderSettings())
                      for g in genomes(cfg, 24, mutations=10)) if p.valid][:6]
    assert len(ps) >= 3
    dims = [c.input_size for c in (p.controller for p in ps)]
    width, acts = max(dims), max(len(p.controller.action_cells) for p in ps)
    obs = np.random.default_rng(1).normal(size=(len(ps), width))
    for i, d in enumerate(dims):
        obs[i, d:] = 0.0
    batch = ControllerBatch([p.controller for p in ps], width, acts).act(obs)
    for i, p in enumerate(ps):
        one = p.controller.reference_act(obs[i, :dims[i]])  # the obvious forward pass
        assert np.max(np.abs(batch[i, :len(one)] - one)) <= 1e-12
        assert np.all((one >= 0.6) & (one <= 1.6))
        # a single controller's act (what a champion replays) is the batched arithmetic, bit for bit
        exact = DenseController.from_json(p.controller.to_json()).act(obs[i, :dims[i]])
        assert np.array_equal(exact, batch[i, :len(one)])
