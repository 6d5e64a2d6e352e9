"""Where a scene's strip lies: the straight hanging chain and the clamp's lowest point.

Coordinates: x to the right, y up, the clamp's top at the origin; node i at (0, −i h).
"""

from __future__ import annotations

import numpy as np

from warpcloth import units

from .schema import Scene


def rest_positions(scene: Scene) -> np.ndarray:
    """Straight hanging strip ``[node, xy]`` (m): node i at (0, −i h)."""
    return np.stack([np.zeros(scene.n_nodes), -scene.spacing * np.arange(scene.n_nodes)], axis=-1)


def clamp_edge(scene: Scene) -> np.ndarray:
    """The clamp's lowest point (origin of rotation-centre, hold and laser offsets), m."""
    return np.array([0.0, -scene.strip.clamp_length_mm * units.LENGTH_MM])
