"""Networks: one genome-to-feed-forward compile, and the forms we run it in (a vectorised CPPN,
a batch of NEAT networks, a JSON graph controller) plus SGR's dense substrate controllers."""

from evolve.nn.activations import NEAT_ACTIVATIONS, PLAIN_ACTIVATIONS, to_action
from evolve.nn.batch import GraphPolicy, NetworkBatch
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.dense import ControllerBatch, DenseController
from evolve.nn.feedforward import FeedForward, compile_genome
from evolve.nn.graph import GraphController

__all__ = ["NEAT_ACTIVATIONS", "PLAIN_ACTIVATIONS", "CompiledCPPN", "ControllerBatch", "DenseController",
           "FeedForward", "GraphController", "GraphPolicy", "NetworkBatch", "compile_genome", "to_action"]
