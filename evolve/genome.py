"""neat-python genome whose speciation distance adds the body distance (SGR paper eq. 1).

distance = NEAT genomic distance + v * body_distance(body, body'). The bodies come from a cache
the search fills (by genome key) before every speciation, so no genome is decoded twice.
"""

from __future__ import annotations

from neat import DefaultGenome

from evolve.body_distance import body_distance


class BodyAwareGenome(DefaultGenome):
    def distance(self, other, config) -> float:
        d = super().distance(other, config)
        v = getattr(config, "body_distance_weight", 0.0)
        if v:
            bodies = config.body_cache
            d += v * body_distance(bodies[self.key], bodies[other.key])
        return d
