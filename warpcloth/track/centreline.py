"""Without markers: the strip's centreline, sampled at given arc lengths.

The strip (seen edge on) and the clamp differ from the background (``|frame − background|``
above the threshold) as one connected region. Its far end from the clamp is the free end:
the pixel of the region farthest, along the region, from the pixel nearest the clamp's
lowest point at rest (Dijkstra on the region's pixels, ``scipy.sparse.csgraph``); the path
back from it runs along the strip. That path, smoothed, is refined across the strip: at
each point the centre of the difference profile along the normal (±2.5 half-widths,
sampled bilinearly), and at the free end where the profile along the strip falls to half
its level. Arc length is measured along the refined centreline in the plane (mm), **from
the free end**: a point at s from the clamp's lowest point is ``free_length − s`` from the
free end, so s is the rest arc length only as far as the strip does not stretch.

Without markers there is no identity to lose; what can fail is the region (no region
reaching the clamp, or a centreline shorter than the arc asked for): an error naming the
frame, never a sample where there is no strip.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from warpcloth.errors import DataFileError

from .calibration import PlaneMapping
from .edges import sample
from .markers import Tracked, noise_sigma
from .video import Frames, FrameStream

__all__ = ["track_centreline"]

STEP_PX = 1.0
SMOOTH = 7
LINE_SMOOTH = 11  # points (px) averaged along the refined line before its arc is measured
ARC_STRIDE = 5  # the arc is summed over chords this many points long
PROFILE_HALF_WIDTHS = 2.5
SEED_REACH_PX = 50
WIDTH_REACH_PX = 200.0  # how far either side of the centreline the strip's width is looked for
WIDTH_ALLOWANCE = 1.25
BLUR_ALLOWANCE_PX = 3.0
"""A strip seen wider than ``WIDTH_ALLOWANCE`` × its thickness and this (px: the blur and the
threshold) shows one of its faces, and the centre of what the camera sees is not the
midline. The bundled video's strip, 1.6 mm thick and seen edge-on, is seen 1.83–1.86 mm
wide (1.1–1.2 px more). On the rig (a strip 25 mm wide and 0.5 mm thick, 450 mm from a
camera 19° from square, scenes/data/rig/edge.mp4) it is seen 7.4–8.8 mm wide, and the
centreline was 2.1 mm off with u 0.017 mm and exit 0; a camera square to it and level
still sees 2.2–2.4 mm at rest, the face its perspective shows 30 mm off its axis."""
VALIDATED_PX = 0.08
"""What validation measures across the strip beyond each point's noise (px; added to its
uncertainty across in quadrature; along it :data:`ARC_VALIDATED_PX`): the profile's
sampling phase. On the bundled example (warpcloth's own renderer, lossless, the strip seen
edge-on, tests/test_track.py) the centreline is off by 0.013 and 0.011 mm RMS in x and y,
~0.06 px, where the noise's share is 0.008 px. Not measured on video warpcloth did not
render of a strip seen edge-on: the rig sees a face (:data:`BLUR_ALLOWANCE_PX`)."""
ARC_VALIDATED_PX = 0.3
"""What validation measures along the strip beyond each point's noise (px): every point is
placed by its arc from the free end, whose error the frame's points share. On the rig's
dyed edge (scenes/data/rig/edge.mp4, benchmarks/track_accuracy.py) the midline is off
along the strip by −0.040 mm (bias) and 0.063 mm RMS, up to 0.24 mm in a frame (the free end
found short: its dyed side face, motion blur and 4:2:0 chroma at the end; the strip's 0.04 %
stretch), against 0.050 mm across: 0.3 px is where u covers 70 % of those errors within 1σ,
94 % within 2σ. The centreline measures its arc the same way and takes the same floor (its
own is not measured on independent video)."""


def _region_path(mask: np.ndarray, seed: tuple[float, float], where: str, path: Path) -> np.ndarray:
    # the pixels (x, y) from the free end back to the seed, along the region holding the seed
    import cv2
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    n, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    ys, xs = np.nonzero(labels)
    if not len(xs):
        raise DataFileError(path, f"{where}: nothing differs from the background by the threshold: no strip")
    nearest = int(np.argmin(np.hypot(xs - seed[0], ys - seed[1])))
    if np.hypot(xs[nearest] - seed[0], ys[nearest] - seed[1]) > SEED_REACH_PX:
        raise DataFileError(
            path,
            f"{where}: nothing differs from the background within {SEED_REACH_PX} px of the "
            "clamp's lowest point at rest: the strip or the clamp is not where the plane file puts "
            "them",
        )
    seed_pixel = (ys[nearest], xs[nearest])
    ys, xs = np.nonzero(labels == labels[seed_pixel])
    index = -np.ones(mask.shape, np.int64)
    index[ys, xs] = np.arange(len(xs))
    rows, cols, weights = [], [], []
    for dy, dx in ((0, 1), (1, -1), (1, 0), (1, 1)):
        y2, x2 = ys + dy, xs + dx
        inside = (y2 < mask.shape[0]) & (x2 >= 0) & (x2 < mask.shape[1])
        target = np.full(len(xs), -1)
        target[inside] = index[y2[inside], x2[inside]]
        ok = target >= 0
        rows.append(np.arange(len(xs))[ok])
        cols.append(target[ok])
        weights.append(np.full(ok.sum(), np.hypot(dx, dy)))
    graph = coo_matrix(
        (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(len(xs), len(xs))
    ).tocsr()
    start = int(index[seed_pixel])
    distance, predecessors = dijkstra(graph, directed=False, indices=start, return_predecessors=True)
    node = int(np.argmax(np.where(np.isfinite(distance), distance, -1)))
    chain = [node]
    while predecessors[node] >= 0:
        node = int(predecessors[node])
        chain.append(node)
    return np.column_stack([xs[chain], ys[chain]]).astype(np.float64)


def _resample(points: np.ndarray, step: float) -> np.ndarray:
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    at = np.arange(0.0, arc[-1], step)
    return np.column_stack([np.interp(at, arc, points[:, 0]), np.interp(at, arc, points[:, 1])])


def smooth_line(points: np.ndarray, width: int) -> np.ndarray:
    """Each point ``[n, 2]`` averaged with its neighbours over ``width`` points, the ends
    repeated beyond the line."""
    kernel = np.ones(width) / width
    return np.column_stack(
        [np.convolve(np.pad(points[:, k], width // 2, mode="edge"), kernel, "valid") for k in range(2)]
    )


def normals(line: np.ndarray) -> np.ndarray:
    """The unit normal ``[n, 2]`` at each point of ``line [n, 2]`` (its tangent turned a
    quarter anticlockwise; the tangent by central differences)."""
    tangent = np.gradient(line, axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1), 1e-12)[:, None]
    return np.column_stack([-tangent[:, 1], tangent[:, 0]])


def _refine(
    difference: np.ndarray, path: np.ndarray, half_width: float, noise: float, threshold: float
) -> tuple[np.ndarray, np.ndarray]:
    # each point moved to the centre of the profile across the strip; its σ from the noise
    smooth = smooth_line(path, SMOOTH)
    normal = normals(smooth)
    offsets = np.arange(-PROFILE_HALF_WIDTHS * half_width, PROFILE_HALF_WIDTHS * half_width + 0.25, 0.25)
    across = smooth[:, None, :] + offsets[None, :, None] * normal[:, None, :]
    weight = np.clip(sample(difference, across.reshape(-1, 2)).reshape(len(smooth), -1) - 0.5 * threshold, 0, None)
    total = weight.sum(axis=1)
    shift = (weight * offsets).sum(axis=1) / total
    # samples 0.25 px apart are correlated over a pixel: count each pixel once
    sigma = noise * np.sqrt((weight > 0) @ (offsets**2) * 0.25) / (total * 0.25) if noise else np.zeros(len(total))
    return smooth + shift[:, None] * normal, sigma


def _free_end(difference: np.ndarray, centre: np.ndarray, half_width: float) -> np.ndarray:
    # where the profile along the strip's direction, continued past its centreline, falls to
    # half the strip's level; centre[0] is a full band's width inside the end
    direction = centre[0] - centre[10]
    direction /= np.linalg.norm(direction)
    along = np.arange(0.0, 8 * half_width + 0.1, 0.1)
    profile = sample(difference, centre[0] + along[:, None] * direction)

    def crossing(level: float) -> float | None:
        below = np.nonzero(profile < 0.5 * level)[0]
        if not len(below) or below[0] == 0:
            return None
        k = int(below[0])
        a, b = profile[k - 1], profile[k]
        return along[k - 1] + (a - 0.5 * level) / (a - b) * (along[k] - along[k - 1])

    cross = crossing(float(np.median(sample(difference, centre[:40]))))
    if cross is None:
        return centre[0]
    # then half the level just inside the end: motion blurs the free end most, which lowers
    # the band's level towards it, and half the level 8 mm up is crossed before the end
    inside = profile[along <= cross - 1.5 * half_width]
    if len(inside) >= 5:
        local = crossing(float(np.median(inside)))
        cross = cross if local is None else local
    return centre[0] + cross * direction


def seen_width_px(mask: np.ndarray, line: np.ndarray) -> float:
    """How wide the region ``mask`` is across ``line`` (px): the median over the line's
    middle half of the run of region pixels along each point's normal through it (the
    clamp and the free end left out)."""
    part = line[len(line) // 4 : 3 * len(line) // 4 + 1]
    normal = normals(smooth_line(part, SMOOTH))
    reach = np.arange(0.0, WIDTH_REACH_PX, 0.5)
    region, runs = mask.astype(np.float32), []
    for sign in (1.0, -1.0):
        inside = sample(region, part[:, None, :] + sign * reach[None, :, None] * normal[:, None, :]) > 0.5
        runs.append(np.argmin(np.column_stack([inside, np.zeros(len(part), bool)]), axis=1) * 0.5)
    return float(np.median(runs[0] + runs[1]))


def _one_frame(
    image: np.ndarray,
    bg: np.ndarray,
    mapping: PlaneMapping,
    seed: np.ndarray,
    s_mm: np.ndarray,
    free_length_mm: float,
    threshold_dn: float | None,
    thickness_mm: float,
    where: str,
    path: Path,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    # the centreline points (px), their σ across and along the strip (px), the frame's
    # noise and how wide the strip is seen (mm)
    import cv2

    difference = np.abs(bg - image.astype(np.float32))
    noise = noise_sigma(bg - image)
    threshold = threshold_dn if threshold_dn is not None else max(10.0 * noise, 5.0)
    mask = difference > threshold
    route = _region_path(mask, seed, where, path)
    # the half-width: the distance to the region's edge at the middle of the strip, the
    # largest within 9 px of the path (a shortest path runs along an edge)
    inside = cv2.dilate(cv2.distanceTransform(mask.astype(np.uint8), cv2.DIST_L2, 5), np.ones((9, 9), np.uint8))
    half_width = max(float(np.median(inside[route[:, 1].astype(int), route[:, 0].astype(int)][: len(route) // 2])), 1.0)
    centre = _resample(route, STEP_PX)
    for _ in range(2):  # the second pass profiles across the first pass's centreline
        centre, sigma = _refine(difference, centre, half_width, noise, threshold)
    # near the free end a profile across sees no full band: start the line 3 half-widths in
    inner = int(np.ceil(3 * half_width / STEP_PX))
    centre, sigma = centre[inner:], sigma[inner:]
    tip = _free_end(difference, centre, half_width)
    # the refined points scatter across by ~0.1 px (the profile's sampling phase): summed
    # over 1 px steps that would lengthen the arc by ~1 %, so the line is averaged over
    # 11 px and its arc summed over 5 px chords (a curvature radius of 20 mm: −0.01 %)
    centre = smooth_line(centre, LINE_SMOOTH)[::ARC_STRIDE]
    sigma = sigma[::ARC_STRIDE] / np.sqrt(LINE_SMOOTH)
    scale = float(np.median(mapping.mm_per_px(centre)))
    width_mm = seen_width_px(mask, centre) * scale
    widest = WIDTH_ALLOWANCE * thickness_mm + BLUR_ALLOWANCE_PX * scale
    if width_mm > widest:
        raise DataFileError(
            path,
            f"{where}: the strip is seen {width_mm:.3g} mm wide across, wider than the {thickness_mm:g} mm "
            f"--thickness-mm allows ({widest:.2g} mm with the blur): the camera sees one of its faces, and the "
            "centre of what it sees is not the strip's midline (a strip 25 mm wide shows 0.44 mm of its face "
            "1° off square): film the strip edge-on from farther away, or dye its near edge and track that (--edge-s)",
        )
    line_px = np.vstack([tip, centre])
    line_mm = mapping.to_plane(line_px)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(line_mm, axis=0), axis=1))])
    wanted = free_length_mm - np.asarray(s_mm)
    if wanted.max() > arc[-1]:
        raise DataFileError(
            path,
            f"{where}: the centreline found is {arc[-1]:.3g} mm long from the free end, "
            f"shorter than the {wanted.max():g} mm to s = {np.min(s_mm):g} mm (--centreline-s, "
            "--free-length-mm)",
        )
    points = np.column_stack([np.interp(wanted, arc, line_px[:, 0]), np.interp(wanted, arc, line_px[:, 1])])
    noise_share = np.interp(wanted, arc, np.concatenate([[sigma[0]], sigma]))
    return points, np.hypot(noise_share, VALIDATED_PX), np.hypot(noise_share, ARC_VALIDATED_PX), noise, width_mm


def track_centreline(
    frames: Frames | FrameStream,
    background: np.ndarray,
    mapping: PlaneMapping,
    s_mm: np.ndarray,
    free_length_mm: float,
    path: str | Path,
    thickness_mm: float,
    threshold_dn: float | None = None,
    progress: bool = False,
    ignore: np.ndarray | None = None,
) -> Tracked:
    """The centreline at arc lengths ``s_mm`` from the clamp's lowest point in every frame
    (see the module docstring); ``frames`` gives ``(index, t, image)`` per frame; nothing
    is looked for where ``ignore`` is set. A frame whose strip is seen wider than the
    fabric's ``thickness_mm`` and the blur allow is an error: the camera sees a face, not
    only the edge (:data:`WIDTH_ALLOWANCE`)."""
    from tqdm import tqdm

    path = Path(path)
    seed = mapping.to_pixels(np.zeros((1, 2)))[0]
    bg = background.astype(np.float32)
    index, t, px, u, u_along, noise, widths = [], [], [], [], [], [], []
    for i, time, image in tqdm(
        frames, total=frames.total, desc="tracking the centreline", unit=" frames", disable=not progress
    ):
        if ignore is not None:  # a masked pixel differs from nothing
            image = np.where(ignore, bg, image)
        points, sigma, sigma_along, frame_noise, width = _one_frame(
            image,
            bg,
            mapping,
            seed,
            s_mm,
            free_length_mm,
            threshold_dn,
            thickness_mm,
            f"frame {i} (t = {time:.6g} s)",
            path,
        )
        index.append(i)
        t.append(time)
        px.append(points)
        u.append(sigma)
        u_along.append(sigma_along)
        noise.append(frame_noise)
        widths.append(width)
    tracked = Tracked.in_plane(mapping, index, t, s_mm, np.array(px), np.array(u), noise, np.array(u_along))
    tracked.seen_width_mm = np.array(widths)
    return tracked
