"""SGR, the paper's method, as one package: one CPPN genome queried HyperNEAT-style over a 3-D
substrate gives a body network (z > 0) and a controller network (z < 0).

- problem.py: the method (`SgrProblem`: config keys, decode, evaluate, champion record);
- decoder.py: a genome to a body and a dense controller (`decode_genome`, `DecoderSettings`);
- hyperneat.py: the CPPN queried over a substrate's links; substrates.py: the substrates' nodes;
- decoders/: the body decoders (the paper's substrate, cppn, fourier, growth);
- record.py: the controller recorded as its genome's decoding (sgr-hyperneat-controller-1).
"""

from evolve.methods.sgr.problem import SgrProblem, settings_of_config

__all__ = ["SgrProblem", "settings_of_config"]
