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

__all__ = ["LOBE_FLOOR", "band_edges", "rising_edges", "sample"]

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


def band_edges(
    profiles: np.ndarray,
    positions: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    iterations: int = 15,
    face: np.ndarray | float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The two edges of a band in each profile ``[ray, sample]`` (samples at ``positions``),
    fitted as two blurred steps: b + a1 Φ((x − e1)/σ) + a2 Φ((x − e2)/σ), from the guesses
    ``first`` < ``second``; returns e1, e2, the first step's height a1 and each fit's RMS
    misfit. The steps' heights are free, so the band may differ from each side by its own
    amount (a dark dye between a grey backdrop and white fabric) or by the same (its
    colour against neutral). A band a few blur widths across has its two edges' lobes
    overlapping, which pulls a lobe's centroid outwards (0.08 px on a 6 px band blurred by
    1.4 px); the fitted steps do not. Gauss–Newton with Levenberg–Marquardt damping, every
    profile at once.

    ``face`` (per profile or one number, in position units) adds a third step of free
    height at e1 + face: a band whose first ``face`` is a surface of its own shade (a dyed
    edge's cut face, the fabric's thickness wide, beside its dyed side face). A narrow
    brighter face is a peak the two-step model cannot follow: it pulls e1 outwards (0.25 px
    with a 2.3 px face 15 % brighter, blurred by 1.4 px)."""
    from scipy.special import ndtr

    n = len(profiles)
    x = positions[None, :]
    low, high = profiles[:, :3].mean(axis=1), profiles[:, -3:].mean(axis=1)
    middle = profiles[np.arange(n), np.clip(np.searchsorted(positions, 0.5 * (first + second)), 0, len(positions) - 1)]
    shift = np.zeros((n, 1)) if face is None else np.broadcast_to(np.asarray(face, dtype=np.float64), (n,))[:, None]
    # parameters: b, a1, a2, e1, e2, σ, then the face's step height a3
    p = np.column_stack(
        [low, middle - low, high - middle, first, second, np.full(n, 1.0)] + [np.zeros(n)] * (face is not None)
    )
    k = p.shape[1]
    damping = np.full(n, 1e-3)

    def residual(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        b, a1, a2, e1, e2, s = (q[:, i : i + 1] for i in range(6))
        a3 = q[:, 6:7] if k == 7 else np.zeros_like(b)
        z1, z2, z3 = (x - e1) / s, (x - e2) / s, (x - e1 - shift) / s
        g1, g2, g3 = (np.exp(-0.5 * z**2) / np.sqrt(2 * np.pi) for z in (z1, z2, z3))
        model = b + a1 * ndtr(z1) + a2 * ndtr(z2) + a3 * ndtr(z3)
        columns = [
            np.ones_like(model),
            ndtr(z1),
            ndtr(z2),
            -(a1 * g1 + a3 * g3) / s,
            -a2 * g2 / s,
            -(a1 * g1 * z1 + a2 * g2 * z2 + a3 * g3 * z3) / s,
        ] + [ndtr(z3)] * (k == 7)
        return model - profiles, np.stack(columns, axis=2)

    r, jac = residual(p)
    cost = np.sum(r**2, axis=1)
    for _ in range(iterations):
        jt = jac.transpose(0, 2, 1)
        jtj = jt @ jac
        jtr = (jt @ r[..., None])[..., 0]
        diagonal = np.einsum("nii->ni", jtj) + 1e-12
        step = -np.linalg.solve(jtj + damping[:, None, None] * np.eye(k) * diagonal[:, :, None], jtr[..., None])[..., 0]
        trial = p + step
        trial[:, 5] = np.maximum(trial[:, 5], 0.05)
        r_trial, jac_trial = residual(trial)
        cost_trial = np.sum(r_trial**2, axis=1)
        better = cost_trial < cost
        p = np.where(better[:, None], trial, p)
        r = np.where(better[:, None], r_trial, r)
        jac = np.where(better[:, None, None], jac_trial, jac)
        cost = np.where(better, cost_trial, cost)
        damping = np.where(better, damping * 0.3, damping * 10.0)
    return p[:, 3], p[:, 4], p[:, 1], np.sqrt(cost / profiles.shape[1])
