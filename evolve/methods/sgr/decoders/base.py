"""The contract of a body decoder: a genome's compiled CPPN -> an (H, W) material grid, at any shape.

SGR draws the body and the controller from one CPPN genome (evolve/methods/sgr/decoder.py). The
controller is always the paper's HyperNEAT controller substrate (z < 0); how the body is drawn is a
choice (config key `body_decoder`): a `BodyDecoder` reads the CPPN's first `body_outputs` output
columns at queries of its own (all at z > 0 or otherwise apart from the controller's) and returns
material codes 0-4 (empty, rigid, soft, H actuator, V actuator). Its few settings (config key
`body_decoder_settings`) are declared in `settings` with their defaults; a champion records them.
A decoder is one module and one line in evolve/methods/sgr/decoders/__init__.py's registry.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from evolve.methods.sgr.hyperneat import Expression
from evolve.nn.cppn import CompiledCPPN
from tsim.errors import SgrError

# a setting: (the types its value may have, its default, the least and the most value of an int;
# the most keeps a typo's extra zeros from hanging a run)
Setting = tuple[tuple[type, ...], Any, int, int]
Settings = tuple[tuple[str, Any], ...]  # resolved settings, sorted by name (hashable, frozen)


class BodyDecoder:
    """Base class of a body decoder (module docstring): set `name`, `body_outputs` and `settings`,
    and implement `body`."""
    name: ClassVar[str]
    body_outputs: ClassVar[int] = 1  # CPPN output columns the body reads: 0 .. body_outputs - 1
    settings: ClassVar[dict[str, Setting]] = {}

    def body(self, cppn: CompiledCPPN, shape: tuple[int, int], expression: Expression,
             settings: Mapping[str, Any]) -> np.ndarray:
        """(H, W) int64 material codes 0-4 at `shape`; not checked: may be empty, disconnected or
        without an actuator. Deterministic and free of side effects."""
        raise NotImplementedError

    @classmethod
    def resolve(cls, raw: Mapping[str, Any] | None, source: str = "config") -> Settings:
        """`raw` (the `body_decoder_settings` key) checked, with the defaults of the settings it
        leaves out; SgrError in one line naming the key and the setting."""
        raw = dict(raw or {})
        key = f"{source}: key 'body_decoder_settings'"
        for name in raw:
            if name not in cls.settings:
                known = ", ".join(cls.settings) or "none"
                raise SgrError(f"{key}: unknown setting {name!r} for body decoder {cls.name!r}; its "
                               f"settings: {known}")
        out = {}
        for name, (types, default, least, most) in cls.settings.items():
            value = raw.get(name, default)
            names = " or ".join("null" if t is type(None) else t.__name__ for t in types)
            if (not isinstance(value, types) or isinstance(value, bool)
                    or isinstance(value, int) and not least <= value <= most):
                raise SgrError(f"{key}: setting {name!r} of body decoder {cls.name!r} must be {names}"
                               f"{f' from {least} to {most:,}' if int in types else ''}, got {value!r}")
            out[name] = value
        return tuple(sorted(out.items()))
