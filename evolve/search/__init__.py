"""NEAT plumbing: the ask/tell search (`NeatSearch`), our neat-python genome and reproduction
classes (body-aware speciation, side-effect-free pickling), and neat-python INI loading."""

from evolve.search.genome import BodyAwareGenome, FlexibleReproduction
from evolve.search.neat_ini import load_neat_config, neat_config_from_text, neat_ini_text
from evolve.search.neat_search import NeatSearch

__all__ = ["BodyAwareGenome", "FlexibleReproduction", "NeatSearch", "load_neat_config",
           "neat_config_from_text", "neat_ini_text"]
