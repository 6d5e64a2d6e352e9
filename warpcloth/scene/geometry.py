"""Where a scene's strip lies: the straight hanging chain, from the clamp edge.

Coordinates: x to the right, y up, the origin at the **clamp edge** (the clamp's lowest
point at rest), where the free strip begins; node i at (0, (n_c − 1 − i) h). Every scene
offset (rotation centre, hold target, laser height, probed hinge), every measured file
and every result (probes, frames, figures, USD) uses this one origin.
"""

from __future__ import annotations

import numpy as np

from .schema import Scene

COORDINATES = "x right, y up, m, from the clamp edge (the clamp's lowest point at rest)"
"""The frame of every position a run or sweep stores, written into its meta.json or
sweep.json; a reader refuses results that do not say it (older ones had the clamp's top
as the origin)."""


def rest_positions(scene: Scene) -> np.ndarray:
    """Straight hanging strip ``[node, xy]`` (m): node i at (0, (n_c − 1 − i) h), so the
    clamp-edge node n_c − 1 is at the origin and the clamp's top at (0, L_c)."""
    above_edge = scene.n_clamped - 1 - np.arange(scene.n_nodes)
    return np.stack([np.zeros(scene.n_nodes), scene.spacing * above_edge], axis=-1)
