"""Sub-pixel edges along profiles, located where the image changes fastest.

An edge between two surfaces, blurred by the lens (symmetric) and by motion during the
exposure (a box along the motion, symmetric about the mid-exposure position), changes
fastest at the true edge whatever the brightness on either side: the gradient of a blurred
step is the blur's kernel, centred on the step, scaled by the step's height. So the edge is
the centroid of the gradient's lobe, not a threshold crossing (which moves with the
contrast: a dark dot against bright fabric on one side and a darker backdrop on the other
would be pulled towards the backdrop), nor a centroid of a clipped darkening (which
weighs the two sides unequally). Used for the markers' outlines (:mod:`.markers`) and the
coloured edge (:mod:`.coloured_edge`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["LOBE_FLOOR", "rising_edges", "sample"]

LOBE_FLOOR = 0.25
"""The lobe is the run of samples around the gradient's peak above this fraction of it;
its centroid weighs each by its excess over the floor, so a symmetric lobe's centroid is
its centre however the floor cuts it."""


def sample(image: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``image`` (2-D, float) bilinearly at ``points [..., 2]`` (x = column, y = row,
    pixel centres at integers), edges replicated."""
    import cv2

    shape = points.shape[:-1]
    flat = points.reshape(-1, 2)
    width = 1024  # remap's maps are images: at most 32767 rows
    n = len(flat)
    maps = np.zeros((-(-n // width) * width, 2), np.float32)
    maps[:n] = flat
    maps = maps.reshape(-1, width, 2)
    values = cv2.remap(
        np.asarray(image, np.float32), maps[..., 0], maps[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
    )
    return values.ravel()[:n].reshape(shape).astype(np.float64)


def rising_edges(profiles: np.ndarray, step: float, least_rise: float) -> tuple[np.ndarray, np.ndarray]:
    """Where each profile ``[ray, sample]`` (samples ``step`` apart) rises most steeply:
    the centroid of the rising lobe around the gradient's largest value, in units of the
    sample position (0 at the first sample), and the lobe's rise (the brightness it gains);
    NaN where it rises by less than ``least_rise`` (no edge there: noise, or the dot's
    outline hidden)."""
    gradient = np.gradient(profiles, step, axis=1)
    n, m = gradient.shape
    peak = np.argmax(gradient, axis=1)
    top = gradient[np.arange(n), peak]
    floor = LOBE_FLOOR * top
    above = gradient > floor[:, None]
    index = np.arange(m)[None, :]
    # the contiguous run of samples above the floor that holds the peak
    below_left = np.where(~above & (index < peak[:, None]), index, -1).max(axis=1)
    below_right = np.where(~above & (index > peak[:, None]), index, m).min(axis=1)
    lobe = (index > below_left[:, None]) & (index < below_right[:, None])
    weight = np.where(lobe, gradient - floor[:, None], 0.0)
    position = (weight * index).sum(axis=1) / np.maximum(weight.sum(axis=1), 1e-300) * step
    rise = np.where(lobe, gradient, 0.0).sum(axis=1) * step
    at_end = (below_left < 0) | (below_right >= m)  # the lobe runs off the profile: not a whole edge
    return np.where((rise >= least_rise) & ~at_end & (top > 0), position, np.nan), rise
