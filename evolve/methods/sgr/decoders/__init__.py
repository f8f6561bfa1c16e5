"""Body decoders behind one contract (`BodyDecoder`, evolve/methods/sgr/decoders/base.py) and their
registry by name (the config key `body_decoder`): a decoder is one module and one line here."""

from __future__ import annotations

from evolve.methods.sgr.decoders.base import BodyDecoder, Settings
from evolve.methods.sgr.decoders.cppn_query import CppnQueryDecoder
from evolve.methods.sgr.decoders.fourier import FourierDecoder
from evolve.methods.sgr.decoders.growth import GrowthDecoder
from evolve.methods.sgr.decoders.substrate import SubstrateDecoder
from tsim.errors import SgrError

DEFAULT = "substrate"  # the SGR paper's
DECODERS: dict[str, BodyDecoder] = {d.name: d for d in (
    SubstrateDecoder(),
    CppnQueryDecoder(),
    FourierDecoder(),
    GrowthDecoder(),
)}


def body_decoder(name: str, source: str = "config") -> BodyDecoder:
    """The decoder registered as `name`; SgrError in one line naming the key and the known ones."""
    try:
        return DECODERS[name]
    except (KeyError, TypeError):
        raise SgrError(f"{source}: key 'body_decoder' must be one of {', '.join(DECODERS)}, "
                       f"got {name!r}") from None


__all__ = ["DECODERS", "DEFAULT", "BodyDecoder", "Settings", "body_decoder"]
