"""SGR's champion controller recorded as what it is a function of: the genome and the decoder's
settings (format sgr-hyperneat-controller-1).

A decoded controller is a pure, deterministic function of the CPPN genome, the decoder settings,
the body and the task (evolve/methods/sgr/decoder.py). Written out as JSON numbers its weights are
most of a champion file: ~45 KB at 5x5, ~500 KB at 10x10 (a 144 x 100 and a 100 x 100 matrix,
97 % of them non-zero, so no sparse or binary encoding gets far below 200 KB). The genome that draws
them is ~1 KB. So champion.json records the genome (its "genome" key, as before), the settings, the
layers' shapes and activations, and a SHA-256 of the weights; reading the file decodes the genome
again and checks the digest, so a champion read back is bit for bit the one evolution scored, or an
error says it is not. Files holding the weights in full (sgr-dense-controller-1) still load as they
are. A body decoder other than the paper's substrate (evolve/methods/sgr/decoders/) is recorded in the
settings as `body_decoder` and `body_decoder_settings`; a record without them (every one written
before decoders were a choice) reads as the substrate's.
"""

from __future__ import annotations

import hashlib

import numpy as np

from evolve.methods.sgr.decoder import DecoderSettings, body_from_cppn, controller_from_cppn
from evolve.methods.sgr.decoders import DEFAULT, body_decoder
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.dense import DenseController
from evolve.nn.genome_record import GenomeKeys, genome_from_record, genome_json

FORMAT = "sgr-hyperneat-controller-1"
CPPN_INPUTS = 7  # x1, y1, z1, x2, y2, z2, bias
DOC = ("The dense controller (sgr-dense-controller-1: x = observation zero-padded by input_padding; for each "
       "layer x = activation(x @ weights + biases)) that SGR's HyperNEAT decoding of this file's 'genome' at "
       "'decoder' gives for its body and task (evolve/methods/sgr/decoder.py); sha256 is that of its weights "
       "and biases as little-endian float64, layer by layer (W then b, W row-major [in][out]). "
       "evolve.load_champion decodes it again and checks the digest.")
DOC_DECODER = (" The body is the one that body decoder 'decoder'.body_decoder, with "
               "'decoder'.body_decoder_settings, draws from the genome (evolve/methods/sgr/decoders/).")


def digest(ctrl: DenseController) -> str:
    """SHA-256 of the controller's numbers: each layer's weights (row-major [in][out]) then biases,
    as little-endian float64."""
    h = hashlib.sha256()
    for W, b in zip(ctrl.weights, ctrl.biases, strict=True):
        h.update(np.ascontiguousarray(W, dtype="<f8").tobytes())
        h.update(np.ascontiguousarray(b, dtype="<f8").tobytes())
    return h.hexdigest()


def _layers(ctrl: DenseController) -> list[dict]:
    pairs = zip(ctrl.weights, ctrl.activations, strict=True)
    return [{"shape": list(W.shape), "activation": a} for W, a in pairs]


def to_json(ctrl: DenseController, s: DecoderSettings) -> dict:
    """The controller decoded with settings `s` as a record of its derivation (module docstring)."""
    decoder = {"shape": list(s.shape), "cppn_outputs": s.cppn_outputs, "weight_threshold": s.threshold,
               "max_weight": s.max_weight}
    if s.body_decoder != DEFAULT:  # the paper's substrate's records stay as they were
        decoder |= {"body_decoder": s.body_decoder, "body_decoder_settings": dict(s.body_settings)}
    return {"format": FORMAT,
            "decoder": decoder,
            "input_size": ctrl.input_size,
            "input_padding": int(ctrl.weights[0].shape[0]) - ctrl.input_size,
            "layers": _layers(ctrl),
            "action_cells": ctrl.action_cells.tolist(),
            "action_map": "action = 1.1 + 0.5 * output[action_cells]",
            "sha256": digest(ctrl),
            "doc": DOC if s.body_decoder == DEFAULT else DOC + DOC_DECODER}


def settings_of(c: dict) -> DecoderSettings:
    """The decoder settings a record names (no `body_decoder`: the paper's substrate); ValueError
    for an unknown decoder or settings it does not take."""
    d = c["decoder"]
    decoder = body_decoder(d.get("body_decoder", DEFAULT), "champion")  # SgrError: a ValueError
    settings = decoder.resolve(d.get("body_decoder_settings"), "champion")
    return DecoderSettings(shape=(int(d["shape"][0]), int(d["shape"][1])),
                           cppn_outputs=int(d["cppn_outputs"]), threshold=float(d["weight_threshold"]),
                           max_weight=float(d["max_weight"]), body_decoder=decoder.name,
                           body_settings=settings)


def rebuild(record: dict) -> DenseController:
    """The controller of a champion record (its "controller" in this format, "genome", "body" and
    "task"), decoded again; ValueError saying what differs when the genome no longer gives the
    recorded body or weights."""
    c = record["controller"]
    s = settings_of(c)
    keys = GenomeKeys(CPPN_INPUTS, s.n_outputs)
    cppn = CompiledCPPN(genome_from_record(record["genome"], keys), keys)
    body = np.asarray(record["body"], dtype=np.int64)
    if body.shape != s.shape or not np.array_equal(body_from_cppn(cppn, s), body):
        raise ValueError(f"the genome decoded at {s.shape[0]}x{s.shape[1]} draws another body than the "
                         "recorded one")
    ctrl = controller_from_cppn(cppn, body, record["task"], s)
    layers = _layers(ctrl)
    if layers != [{"shape": list(L["shape"]), "activation": L["activation"]} for L in c["layers"]]:
        raise ValueError(f"the genome decodes to layers {layers}, not the recorded ones")
    if ctrl.input_size != int(c["input_size"]) or ctrl.action_cells.tolist() != list(c["action_cells"]):
        raise ValueError("the genome decodes to another input size or other action cells than recorded")
    if digest(ctrl) != c["sha256"]:
        raise ValueError("decoding the genome no longer gives the recorded weights (sha256 differs): "
                         "this sgr decodes differently from the one that wrote the file")
    return ctrl


def recorded(genome, ctrl: DenseController, s: DecoderSettings, body: np.ndarray, task: str) -> dict:
    """The record of `ctrl` (decoded from `genome` with `s`) in this format when decoding the
    genome's JSON record gives it back bit for bit, which is checked here, else in full
    (sgr-dense-controller-1): a written champion always reads back as the controller evolution
    scored."""
    c = to_json(ctrl, s)
    try:  # the digest is of the exact bytes: a rebuild that passes is bit for bit
        rebuild({"controller": c, "genome": genome_json(genome), "body": body.tolist(), "task": task})
    except ValueError:
        return ctrl.to_json()
    return c
