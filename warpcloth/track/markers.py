"""Dark markers on the strip: found in each frame, centred to a fraction of a pixel, and
kept in their order along the strip.

A marker is a connected region darker than the background by more than a threshold
(``cv2.connectedComponentsWithStats``) whose area is that of a marker of the given
diameter (within 0.3× to 4×, room for motion blur). Its position is the centroid of the
darkening (background − frame, clipped at 0) over the region grown by 2 px, so partly
covered edge pixels count by their coverage; its standard uncertainty follows from the
sensor noise, estimated from the frame − background difference itself (the MAD), as
σ_x = σ_n √Σ(x − x̄)² / Σw. Positions map to the strip's plane by the calibration
(:class:`~warpcloth.track.calibration.PlaneMapping`).

Identity is the order along the strip, which markers on a strip cannot change: in each
frame the chain starts at the blob nearest where the first marker was, within half the
spacing of the first two markers (in the first frame: near the clamp's lowest point at
rest, within its s and that), and steps to the nearest remaining blob, each step no longer
than the arc between the two markers (+5 % and 1 mm) and no shorter than 0.3 of it. A
marker the chain cannot reach is lost: an error naming the frame, its time and the
marker, never a shapes file with a gap or a swapped identity.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.io.measured import ALONG_COLUMN

from .calibration import PlaneMapping
from .edges import rising_edges, sample
from .video import Frames, FrameStream

__all__ = ["Tracked", "noise_sigma", "track_markers"]

RAYS = 64
VALIDATED_PX = 0.05
"""What the validation on video warpcloth did not render measures beyond each dot's own
share (px, per coordinate; added in quadrature): on the independent rig
(scenes/data/rig/, H.264, a lens that is not OpenCV's, benchmarks/track_accuracy.py) the
markers are off by 0.013 mm RMS where the outline's share is 0.009 mm: the calibration and
the codec's blocks, 0.009 mm ≈ 0.045 px at its 0.2 mm/px."""
AREA_RANGE = (0.3, 4.0)
STRETCH = 1.05  # a chord may exceed its arc by this factor (strain, detection) plus SLACK_MM
SLACK_MM = 1.0
SHORTEST = 0.3


@dataclass
class Tracked:
    """Markers per frame: pixels and plane positions ``[frame, marker, 2]`` (px, mm), and
    the standard uncertainty of each position (px, mm, per coordinate). A curve's points
    (the dyed edge, the centreline) also carry ``u_along_mm``, their uncertainty along the
    strip, and then ``u_px, u_mm`` are across it (:data:`warpcloth.io.measured.ALONG_COLUMN`)."""

    frame: np.ndarray
    t: np.ndarray
    s_mm: np.ndarray
    px: np.ndarray
    mm: np.ndarray
    u_px: np.ndarray
    u_mm: np.ndarray
    noise_dn: np.ndarray  # the sensor noise estimated in each frame
    u_along_mm: np.ndarray | None = None
    seen_width_mm: np.ndarray | None = None  # a centreline's strip, how wide it is seen in each frame

    @classmethod
    def in_plane(
        cls,
        mapping: PlaneMapping,
        index: list[int],
        t: list[float],
        s_mm: np.ndarray,
        px: np.ndarray,
        u_px: np.ndarray,
        noise_dn: list[float],
        u_along_px: np.ndarray | None = None,
    ) -> Tracked:
        """The points ``px [frame, point, 2]`` with their σ ``u_px`` (and a curve's along the
        strip, ``u_along_px``) mapped to the plane (mm); a point hidden in a frame (NaN) stays NaN."""
        n, m = u_px.shape
        mm, u_mm = np.full((n, m, 2), np.nan), np.full((n, m), np.nan)
        seen = np.isfinite(px[..., 0])
        mm[seen] = mapping.to_plane(px[seen])
        scale = mapping.mm_per_px(px[seen])
        u_mm[seen] = u_px[seen] * scale
        u_along_mm = None
        if u_along_px is not None:
            u_along_mm = np.full((n, m), np.nan)
            u_along_mm[seen] = u_along_px[seen] * scale
        s_mm = np.asarray(s_mm, dtype=float)
        return cls(np.array(index), np.array(t), s_mm, px, mm, u_px, u_mm, np.array(noise_dn), u_along_mm)

    @property
    def columns(self) -> str:
        """The header of :meth:`csv_rows`."""
        return "frame,t_s,s_mm,x_mm,y_mm,u_px,u_mm" + ("" if self.u_along_mm is None else f",{ALONG_COLUMN}")

    def csv_rows(self) -> list[str]:
        """:attr:`columns` rows, none for a marker hidden in a frame."""
        rows = []
        for f, frame in enumerate(self.frame):
            for m, s in enumerate(self.s_mm):
                x, y = self.mm[f, m]
                if not np.isfinite(x):  # hidden in this frame: no row
                    continue
                along = "" if self.u_along_mm is None else f",{self.u_along_mm[f, m]:.5f}"
                rows.append(
                    f"{frame},{self.t[f]:.9f},{s:g},{x:.5f},{y:.5f},{self.u_px[f, m]:.4f},{self.u_mm[f, m]:.5f}{along}"
                )
        return rows


def noise_sigma(darkening: np.ndarray) -> float:
    """The noise of a frame − background difference: the standard deviation of the values
    within 4σ of the median, σ started at 1.4826 × the median absolute deviation and
    iterated three times (the markers, the strip and the clamp are a few per cent of the
    pixels and fall outside; the MAD alone is too coarse on 8-bit integers)."""
    centre = float(np.median(darkening))
    sigma = max(1.4826 * float(np.median(np.abs(darkening - centre))), 0.5)
    for _ in range(3):
        inside = darkening[np.abs(darkening - centre) <= 4 * sigma]  # ≤: a noiseless frame keeps its pixels
        centre, sigma = float(inside.mean()), float(inside.std())
    return sigma


def _blobs(
    darkening: np.ndarray, threshold: float, areas: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray, list[int], np.ndarray]:
    # the marker-sized dark blobs' rough centres and pixel covariances, the areas of the
    # others (px²), and where the dark regions larger than a marker are (the clamp, a hand)
    import cv2

    mask = (darkening > threshold).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    centres, shapes, others = [], [], []
    large = stats[:, cv2.CC_STAT_AREA] > areas[1]
    large[0] = False
    for label in range(1, n):
        x0, y0, w, h, area = stats[label]
        if not areas[0] <= area <= areas[1]:
            others.append(int(area))
            continue
        rows, cols = np.nonzero(labels[y0 : y0 + h, x0 : x0 + w] == label)
        points = np.column_stack([cols + x0, rows + y0]).astype(float)
        centres.append(points.mean(axis=0))
        # a pixel is a unit square: its own spread (1/12) adds to the region's
        shapes.append(np.cov(points.T, bias=True) + np.eye(2) / 12.0)
    return np.array(centres).reshape(-1, 2), np.array(shapes).reshape(-1, 2, 2), others, large[labels]


def _outline(
    grey: np.ndarray, centre: np.ndarray, shape: np.ndarray, noise: float, diameter_px: float
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The centre of a dark dot's outline (px), its standard uncertainty per axis (px) and
    the outline's RMS misfit to an ellipse (px), or None when no dot's outline is there.

    The outline is found on RAYS rays from the rough centre, each where the image rises
    most steeply from the dark dot to whatever surrounds it (:func:`.edges.rising_edges`:
    unbiased whatever the brightness on either side), out to 1.8 times the
    radius the blob's shape gives (room for motion blur) plus 3 px; an ellipse is fitted to
    the edge points (``cv2.fitEllipseDirect``), points off it by more than 4 × the median
    misfit dropped, and the rays cast again from its centre. The centre's uncertainty is
    the least-squares one for the points' misfit, counting at most one point per pixel of
    the outline's length (adjacent rays share pixels), and the outline's lopsidedness added
    in quadrature (:func:`_lopsidedness`: a dot smeared by motion into an edge of the
    fabric is off by about as much as its outline is lopsided; measured in
    tests/test_track_markers.py). An ellipse whose short axis is not the dot's diameter
    ``diameter_px`` (within 0.6 to 1.5 of it; motion only lengthens the long axis) is not a
    dot: a sliver of a moving clamp, two dots merged."""
    angles = np.linspace(0.0, 2 * np.pi, RAYS, endpoint=False)
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    inverse = np.linalg.inv(4.0 * shape)  # a uniform ellipse's covariance is its semi-axes² / 4
    for least in (0.4, 0.6):  # the second pass, centred on the first's dot, must find most rays
        radius = 1.0 / np.sqrt(np.einsum("ri,ij,rj->r", directions, inverse, directions))
        steps = np.arange(0.0, 1.0 + 1e-9, 1.0 / 48)
        reach = (1.8 * radius[:, None] + 3.0) * steps[None, :]
        along = reach[:, 1] - reach[:, 0]
        profiles = sample(grey, centre + reach[..., None] * directions[:, None, :])
        # each ray's own sample spacing: position in samples × its spacing
        at, _ = rising_edges(profiles, 1.0, 6.0 * noise)
        found = np.isfinite(at)
        if found.sum() < least * RAYS:
            return None
        points = centre + (reach[found, 0] + at[found] * along[found])[:, None] * directions[found]
        fitted = _ellipse(points)
        if fitted is None:
            return None
        centre, semi, axes, local, misfit = fitted
        shape = axes.T @ np.diag(semi**2 / 4.0) @ axes
        inverse = np.linalg.inv(4.0 * shape)
    # outward normals of the ellipse at the points: a centre shift δ moves each residual by −n·δ
    normal = (local / semi) @ axes
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    if not 0.6 * diameter_px <= 2.0 * semi.min() <= 1.5 * diameter_px:
        return None
    rms = float(np.sqrt(np.mean(misfit**2)))
    perimeter = np.pi * (3 * semi.sum() - np.sqrt((3 * semi[0] + semi[1]) * (semi[0] + 3 * semi[1])))
    independent = min(len(normal), perimeter)
    covariance = np.linalg.inv(normal.T @ normal) * rms**2 * len(normal) / independent
    return centre, np.sqrt(np.diag(covariance) + _lopsidedness(local, misfit) ** 2 / 2.0 + VALIDATED_PX**2), rms


def _lopsidedness(local: np.ndarray, misfit: np.ndarray) -> float:
    # the amplitude of the misfit's 3rd and 5th harmonics around the outline (px): a blurred
    # or half-covered dot is lopsided where something differs on one side, and a centre is
    # off by about what makes it so; a symmetric departure (even harmonics: motion blur's
    # stadium, a square dot) moves no centre, and the 1st is the centre itself
    angle = np.arctan2(local[:, 1], local[:, 0])
    basis = np.column_stack([np.ones_like(angle)] + [f(k * angle) for k in (2, 3, 4, 5) for f in (np.cos, np.sin)])
    coefficient, *_ = np.linalg.lstsq(basis, misfit, rcond=None)
    return float(np.hypot.reduce(coefficient[[3, 4, 7, 8]]))


def _ellipse(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    # the ellipse through the edge points, outliers (beyond 4 × the median misfit) dropped
    # and refitted until none is: centre, semi-axes, rotation (rows: the axes), each kept
    # point in axis units and its misfit (px); None if too few points stay on one ellipse
    import cv2

    while True:
        (cx, cy), (width, height), angle = cv2.fitEllipseDirect(points.astype(np.float32))
        if not (np.isfinite([cx, cy, width, height]).all() and min(width, height) > 0):
            return None
        centre, semi = np.array([cx, cy]), 0.5 * np.array([width, height])
        rot = np.radians(angle)
        axes = np.array([[np.cos(rot), np.sin(rot)], [-np.sin(rot), np.cos(rot)]])
        local = (points - centre) @ axes.T / semi
        rho = np.linalg.norm(local, axis=1)
        misfit = (rho - 1.0) * np.linalg.norm(points - centre, axis=1) / np.maximum(rho, 1e-12)
        keep = np.abs(misfit) <= 4.0 * max(float(np.median(np.abs(misfit))), 0.02)
        if keep.all():
            return centre, semi, axes, local, misfit
        if keep.sum() < 0.4 * RAYS:
            return None
        points = points[keep]


def _marker_areas(mapping: PlaneMapping, diameter_mm: float) -> tuple[float, float, float]:
    # the area a marker covers at the image's centre and the range taken as one (px²), or
    # an error naming the diameter when no marker of it could be seen in these frames
    centre_px = np.array([[mapping.image_size[0] / 2, mapping.image_size[1] / 2]])
    scale = float(mapping.mm_per_px(centre_px)[0])
    radius_px = 0.5 * diameter_mm / scale
    if not 0.5 <= radius_px <= 0.5 * min(mapping.image_size):
        raise ArgumentError(
            "diameter_mm",
            f"{diameter_mm:g} mm is {2 * radius_px:.3g} px across at the image's centre ({scale:.3g} mm/px): a "
            f"marker must span at least a pixel and fit in the {mapping.image_size[0]} × {mapping.image_size[1]} px "
            "frame; give the markers' diameter in mm",
        )
    area = np.pi * radius_px**2
    return area, AREA_RANGE[0] * area, AREA_RANGE[1] * area


def _check_first_marker(plane: np.ndarray, s_mm: np.ndarray, where: str) -> None:
    # in the first frame the strip hangs at rest from the clamp: its first marker is as far
    # from the clamp's lowest point as its arc length says (a strip is straight over its
    # first marker's few mm), or every marker's label is shifted
    chord = float(np.linalg.norm(plane[0]))
    if not s_mm[0] / STRETCH - SLACK_MM <= chord <= STRETCH * s_mm[0] + SLACK_MM:
        raise ArgumentError(
            "s_mm",
            f"the first marker, labelled s = {s_mm[0]:g} mm, is {chord:.3g} mm from the clamp's lowest point in "
            f"{where}, where the strip hangs at rest: the arc lengths are shifted (each marker would be labelled "
            f"{s_mm[0] - chord:+.3g} mm from where it is), or the plane's origin (--plane) is not the clamp's "
            "lowest point, or the blob is not a marker (a background model that holds the strip or the clamp: "
            "give --background)",
        )


def _chain(plane: np.ndarray, start: np.ndarray, reach: float, s_mm: np.ndarray, where: str, path: Path) -> np.ndarray:
    # indices into `plane` of the markers in their order along the strip
    if not len(plane):
        raise DataFileError(
            path, f"{where}: no marker found (none darker than the background by the threshold, with a marker's area)"
        )
    first = int(np.argmin(np.linalg.norm(plane - start, axis=1)))
    if np.linalg.norm(plane[first] - start) > reach:
        raise DataFileError(
            path,
            f"{where}: marker s = {s_mm[0]:g} mm lost: no dark blob within {reach:.3g} mm of "
            f"where it was (x = {start[0]:.2f}, y = {start[1]:.2f} mm); the nearest is "
            f"{np.linalg.norm(plane[first] - start):.3g} mm away (a background model that holds the clamp "
            "turned hides what is beside it: give --background, a frame without the strip)",
        )
    order = [first]
    left = set(range(len(plane))) - set(order)
    for i in range(1, len(s_mm)):
        arc = s_mm[i] - s_mm[i - 1]
        if left:
            candidates = sorted(left, key=lambda j: np.linalg.norm(plane[j] - plane[order[-1]]))
            chord = float(np.linalg.norm(plane[candidates[0]] - plane[order[-1]]))
            if SHORTEST * arc <= chord <= STRETCH * arc + SLACK_MM:
                order.append(candidates[0])
                left.discard(candidates[0])
                continue
            seen = f"the nearest other dark blob is {chord:.3g} mm from it"
        else:
            seen = "no other dark blob is left"
        extra = (
            ", or the background holds the strip or the clamp where this frame has none (a median of frames in "
            "which they rest: give --background)"
            if len(plane) > len(s_mm)
            else ""
        )
        raise DataFileError(
            path,
            f"{where}: marker s = {s_mm[i]:g} mm lost: it should be within "
            f"{STRETCH * arc + SLACK_MM:.3g} mm of the marker at s = {s_mm[i - 1]:g} mm "
            f"(at x = {plane[order[-1], 0]:.2f}, y = {plane[order[-1], 1]:.2f} mm), but {seen} "
            f"({len(plane)} marker-sized blobs in this frame for {len(s_mm)} markers): it is hidden "
            f"or merged with another, or --marker-s or the plane's scale (--plane) is wrong{extra}",
        )
    return np.array(order)


def _check_chain(plane: np.ndarray, order: np.ndarray, s_mm: np.ndarray, where: str, path: Path) -> None:
    # markers followed one by one must still lie along the strip: each within its arc of the
    # one before (a swap or a stray dot taken for a marker breaks this)
    for i in range(1, len(s_mm)):
        arc = s_mm[i] - s_mm[i - 1]
        chord = float(np.linalg.norm(plane[order[i]] - plane[order[i - 1]]))
        if not SHORTEST * arc <= chord <= STRETCH * arc + SLACK_MM:
            raise DataFileError(
                path,
                f"{where}: marker s = {s_mm[i]:g} mm lost: the dot nearest where it was heading is {chord:.3g} mm "
                f"from the marker at s = {s_mm[i - 1]:g} mm, which the strip between them ({arc:g} mm) cannot "
                "span: a stray dark spot was taken for it (give --mask over moving parts such as the clamp)",
            )


def _follow(
    plane: np.ndarray,
    heading: np.ndarray,
    reach: float,
    s_mm: np.ndarray,
    where: str,
    path: Path,
    may_hide: np.ndarray,
) -> np.ndarray:
    # indices into `plane` of the markers (−1: hidden), each the dot nearest where its own
    # motion was heading, every dot taken once (the assignment of least total distance); a
    # marker with no dot within reach is hidden if `may_hide` allows it, else lost (an
    # error); a hidden marker is taken back only by a dot no other marker took that its
    # seen neighbours along the strip allow, when there is exactly one; then the markers
    # seen are checked along the strip
    from scipy.optimize import linear_sum_assignment

    far = 1e6
    distance = np.linalg.norm(heading[:, None, :] - plane[None, :, :], axis=2).reshape(len(s_mm), len(plane))
    cost = np.where(distance <= reach, distance, far)
    if cost.shape[1] < len(s_mm):
        cost = np.hstack([cost, np.full((len(s_mm), len(s_mm) - cost.shape[1]), far)])
    rows, cols = linear_sum_assignment(cost)
    order = np.full(len(s_mm), -1)
    for m, j in zip(rows, cols, strict=True):
        if cost[m, j] < far:
            order[m] = j
        elif not may_hide[m]:
            nearest = f"{distance[m].min():.3g} mm away" if distance.shape[1] else "none in this frame"
            raise DataFileError(
                path,
                f"{where}: marker s = {s_mm[m]:g} mm lost: no dot within {reach:.3g} mm of where its motion was "
                f"heading (x = {heading[m, 0]:.2f}, y = {heading[m, 1]:.2f} mm; the nearest dot is {nearest}) and "
                "nothing that could hide it near: it is blurred beyond a dot's shape or merged with another; or "
                "moving parts darken the frame against the background (give --background, a frame without the "
                "strip, or --mask over them)",
            )
    left = sorted(set(range(len(plane))) - set(order[order >= 0].tolist()))
    for m in np.flatnonzero(order < 0):
        allowed = [j for j in left if _between_neighbours(plane, order, j, m, s_mm)]
        if len(allowed) == 1:
            order[m] = allowed[0]
            left.remove(allowed[0])
    seen = order >= 0
    _check_chain(plane, order[seen], s_mm[seen], where, path)
    return order


def _between_neighbours(plane: np.ndarray, order: np.ndarray, j: int, m: int, s_mm: np.ndarray) -> bool:
    # whether dot j could be marker m: within the strip's reach of m's nearest seen
    # neighbours on either side (at least one seen)
    checked = 0
    for step in (-1, 1):
        k = m + step
        while 0 <= k < len(s_mm) and order[k] < 0:
            k += step
        if not 0 <= k < len(s_mm):
            continue
        arc = abs(s_mm[k] - s_mm[m])
        chord = float(np.linalg.norm(plane[j] - plane[order[k]]))
        if not SHORTEST * arc <= chord <= STRETCH * arc + SLACK_MM:
            return False
        checked += 1
    return checked > 0


def _carried(estimate: np.ndarray, seen: np.ndarray, previous: np.ndarray, s_mm: np.ndarray) -> np.ndarray:
    # hidden markers placed along the strip through the two nearest seen markers (the strip
    # between markers is nearly straight), or moved as the one seen marker moved
    out = estimate.copy()
    visible = np.flatnonzero(seen)
    for m in np.flatnonzero(~seen):
        if len(visible) >= 2:
            k1, k2 = visible[np.argsort(np.abs(s_mm[visible] - s_mm[m]))[:2]]
            out[m] = estimate[k1] + (estimate[k1] - estimate[k2]) * (s_mm[m] - s_mm[k1]) / (s_mm[k1] - s_mm[k2])
        elif len(visible):
            out[m] = previous[m] + estimate[visible[0]] - previous[visible[0]]
        else:
            out[m] = previous[m]
    return out


def track_markers(
    frames: Frames | FrameStream,
    background: np.ndarray,
    mapping: PlaneMapping,
    s_mm: np.ndarray,
    diameter_mm: float,
    path: str | Path,
    threshold_dn: float | None = None,
    progress: bool = False,
    ignore: np.ndarray | None = None,
) -> Tracked:
    """Every marker in every frame (see the module docstring); ``frames`` gives
    ``(index, t, image)`` per frame, in memory or streamed; ``ignore`` (bool, the frames'
    shape) marks pixels where no marker is looked for (moving parts of the rig): a dot
    touching it is not measured (part of it may be hidden), and a marker heading under it
    is hidden in that frame (NaN in the result), not lost."""
    import cv2
    from tqdm import tqdm

    path = Path(path)
    expected_area, *areas = _marker_areas(mapping, diameter_mm)
    index, t, px, sig, noise = [], [], [], [], []
    estimates: list[np.ndarray] = []  # each frame's marker positions (mm), hidden ones carried
    seen = np.ones(len(s_mm), bool)  # which markers the last frame saw
    bg = _grey(background)
    reach = 0.5 * float(np.min(np.diff(s_mm)))
    touching = shade = None
    diameter_px = 2.0 * np.sqrt(expected_area / np.pi)
    grow = np.ones((2 * int(np.ceil(0.5 * diameter_px)) + 5,) * 2, np.uint8)
    if ignore is not None:
        touching = cv2.dilate(ignore.astype(np.uint8), grow).astype(bool)
        shade = cv2.dilate(touching.astype(np.uint8), grow).astype(bool)
    for i, time, image in tqdm(frames, total=frames.total, desc="tracking", unit=" frames", disable=not progress):
        grey = _grey(image)
        darkening = bg - grey
        if ignore is not None:
            darkening[ignore] = 0.0
        noise.append(noise_sigma(darkening))
        threshold = threshold_dn if threshold_dn is not None else max(10.0 * noise[-1], 5.0)
        rough, shapes, others, occluding = _blobs(darkening, threshold, tuple(areas))
        if touching is not None and len(rough):
            clear = ~_at_pixels(touching, rough)
            rough, shapes = rough[clear], shapes[clear]
        # a dot that reaches into a dark region larger than a marker merges with it: a marker
        # heading there is hidden (behind the clamp as it turns), as under the mask
        shadow = cv2.dilate(occluding.astype(np.uint8), grow).astype(bool)
        if shade is not None:
            shadow |= shade
        where = f"frame {i} (t = {time:.6g} s)"
        if not index and len(rough) < len(s_mm) / 2 and others:  # most missing: not one hidden marker
            raise ArgumentError(
                "diameter_mm",
                f"{diameter_mm:g} mm: {where} holds {len(rough)} blobs of a marker's area ({expected_area:.3g} px², "
                f"taken from {areas[0]:.3g} to {areas[1]:.3g}) for {len(s_mm)} markers, and {len(others)} dark blobs "
                f"of other areas (median {np.median(others):.3g} px², a disc of "
                f"{diameter_mm * np.sqrt(np.median(others) / expected_area):.3g} mm): give the markers' diameter",
            )
        across = diameter_mm / mapping.mm_per_px(rough) if len(rough) else []
        dots = [_outline(grey, c, shape, noise[-1], d) for c, shape, d in zip(rough, shapes, across, strict=True)]
        dots = [d for d in dots if d is not None]  # a dark blob with no dot's outline is not a marker
        centres = np.array([d[0] for d in dots]).reshape(-1, 2)
        plane = mapping.to_plane(centres) if len(centres) else centres
        if not index:
            # the first frame: the strip hangs at rest from the clamp, straight down; markers
            # that would lie under the mask there are hidden, the others in view; the chain
            # starts near the clamp's lowest point, within the first marker's arc and one
            # spacing (a first arc off by a spacing is then named by _check_first_marker)
            at_rest = np.column_stack([np.zeros(len(s_mm)), -s_mm])
            order = np.full(len(s_mm), -1)
            view = np.ones(len(s_mm), bool) if shade is None else ~_at_pixels(touching, mapping.to_pixels(at_rest))
            if view.sum() < 2:
                raise ArgumentError("--mask", "covers all but one of the markers where the strip hangs at rest")
            first, second = s_mm[view][:2]
            order[view] = _chain(plane, at_rest[view][0] + [0.0, first], second, s_mm[view], where, path)
            _check_first_marker(plane[order[view]], s_mm[view], where)
        else:
            heading = estimates[-1]
            if len(estimates) > 1:  # at the speed it had, over this frame's interval
                heading = heading + (estimates[-1] - estimates[-2]) * (time - t[-1]) / (t[-1] - t[-2])
            # within reach of the shadow: where the marker is, within its heading's reach, may be in it
            heading_px = mapping.to_pixels(heading)
            to_shadow = cv2.distanceTransform((~shadow).astype(np.uint8), cv2.DIST_L2, 5)
            reach_px = reach / mapping.mm_per_px(heading_px)
            # and a marker hidden in the last frame stays hidden until it is seen again
            may_hide = (_values_at(to_shadow, heading_px, np.inf) <= reach_px) | ~seen
            order = _follow(plane, heading, reach, s_mm, where, path, may_hide)
        seen = order >= 0
        found = np.full((len(s_mm), 2), np.nan)
        found[seen] = centres[order[seen]]
        sigma = np.full((len(s_mm), 2), np.nan)
        sigma[seen] = [dots[k][1] for k in order[seen]]
        estimate = np.full((len(s_mm), 2), np.nan)
        estimate[seen] = plane[order[seen]]
        # hidden markers: where they hang at rest in the first frame, then carried along
        if estimates:
            estimates.append(_carried(estimate, seen, estimates[-1], s_mm))
        else:
            estimates.append(np.where(seen[:, None], estimate, at_rest))
        index.append(i)
        t.append(time)
        px.append(found)
        sig.append(sigma)
    u_px = np.sqrt(0.5 * np.sum(np.array(sig) ** 2, axis=2))  # per coordinate, from the two axes
    return Tracked.in_plane(mapping, index, t, s_mm, np.array(px), u_px, noise)


def _values_at(image: np.ndarray, pixels: np.ndarray, outside: object) -> np.ndarray:
    # the image's value at each pixel position (x, y), `outside` beyond the frame
    col, row = np.rint(pixels[:, 0]).astype(int), np.rint(pixels[:, 1]).astype(int)
    inside = (row >= 0) & (row < image.shape[0]) & (col >= 0) & (col < image.shape[1])
    out = np.full(len(pixels), outside, dtype=image.dtype if image.dtype != bool else bool)
    out[inside] = image[row[inside], col[inside]]
    return out


def _at_pixels(mask: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    # mask's value at each pixel position (x, y), False outside the frame
    return _values_at(mask, pixels, False)


def _grey(image: np.ndarray) -> np.ndarray:
    # a frame's brightness (float): grey as it is, colour as OpenCV weighs it (RGB order)
    import cv2

    if image.ndim == 3:
        image = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2GRAY)
    return image.astype(np.float64)
