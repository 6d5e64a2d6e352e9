"""Drawable geometry shared by the USD export and the renders: ribbons of the strip's
real width, the clamp's box, and colours per variant (all SI metres)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from warpcloth.io.recording import Recording

CLAMP_JAW_M = 3.0e-3  # drawn thickness of each clamp jaw
BOX_QUADS = [0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4, 1, 5, 7, 3]
"""Quads of the clamp box, 4 corner indices each, outward-facing."""
BOX_FACES = np.hstack([[4, *BOX_QUADS[4 * k : 4 * k + 4]] for k in range(6)])
"""The clamp box's quads as a VTK face array (each quad's corner count, then its corners)."""


def variant_colours(values: np.ndarray) -> np.ndarray:
    """RGB in [0, 1] per value, from the viridis map over the values' range."""
    from matplotlib import colormaps

    values = np.asarray(values, dtype=float)
    span = np.ptp(values) if len(values) else 0.0
    scaled = (values - values.min()) / span if span > 0 else np.full(len(values), 0.5)
    return colormaps["viridis"](scaled)[:, :3]


def colour_values(recording: Recording) -> np.ndarray:
    """What colours the variants: the first parameter that differs between them, else
    the variant number."""
    if not recording.varying:
        return recording.variants.astype(float)
    column = recording.parameters[recording.varying[0]]
    # a choice (e.g. the bending law) colours by its values' order of appearance
    return (
        column.to_numpy(dtype=float) if pd.api.types.is_numeric_dtype(column) else pd.factorize(column)[0].astype(float)
    )


def points3(xy: np.ndarray) -> np.ndarray:
    """(x, y) → (x, y, 0) as float32, the precision USD points and VTK meshes use."""
    out = np.zeros((*xy.shape[:-1], 3), dtype=np.float32)
    out[..., :2] = xy
    return out


def ribbon_vertices(xy: np.ndarray, width: float) -> np.ndarray:
    """Vertices of a ribbon of ``width`` (m) along nodes ``xy``: for node i, 2i at
    z = −W/2 and 2i + 1 at z = +W/2."""
    p = points3(xy)
    edge = np.repeat(p[:, None], 2, axis=1)
    edge[:, 0, 2], edge[:, 1, 2] = -width / 2, width / 2
    return edge.reshape(-1, 3)


def ribbon_quads(n_nodes: int) -> tuple[list[int], list[int]]:
    """Face vertex counts and indices of the ribbon's quads (one per segment)."""
    counts = [4] * (n_nodes - 1)
    indices = []
    for i in range(n_nodes - 1):
        indices += [2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2]
    return counts, indices


def clamp_box(recording: Recording, j: int) -> np.ndarray:
    """The 8 corners of the clamp's jaws at rest (from the clamp edge up to its top)."""
    scene = recording.scenes[j]
    length = scene.strip.clamp_length_mm * 1e-3
    half_w = scene.strip.width_mm * 1e-3 / 2
    return box_corners(np.array([-CLAMP_JAW_M, 0.0, -half_w]), np.array([CLAMP_JAW_M, length, half_w]))


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The 8 corners of the axis-aligned box from ``lo`` to ``hi`` (xyz), in BOX_QUADS' order."""
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], dtype=float)


def sheet_clamp_box(rest_positions: np.ndarray, clamped: np.ndarray) -> np.ndarray:
    """The 8 corners of a sheet's clamp jaws at rest: around every node it holds (``clamped``
    of ``rest_positions`` ``[node, xyz]``), CLAMP_JAW_M either side of the sheet's plane and
    reaching as far past its held nodes, so the jaws show beyond the fabric they grip."""
    held = rest_positions[clamped]
    pad = np.array([CLAMP_JAW_M, 0.0, CLAMP_JAW_M])
    return box_corners(held.min(axis=0) - pad, held.max(axis=0) + pad)
