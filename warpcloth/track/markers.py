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

from .calibration import PlaneMapping
from .video import Frames, FrameStream

__all__ = ["Tracked", "noise_sigma", "track_markers"]

GROW_PX = 2
AREA_RANGE = (0.3, 4.0)
STRETCH = 1.05  # a chord may exceed its arc by this factor (strain, detection) plus SLACK_MM
SLACK_MM = 1.0
SHORTEST = 0.3


@dataclass
class Tracked:
    """Markers per frame: pixels and plane positions ``[frame, marker, 2]`` (px, mm), and
    the standard uncertainty of each position (px, mm, per coordinate)."""

    frame: np.ndarray
    t: np.ndarray
    s_mm: np.ndarray
    px: np.ndarray
    mm: np.ndarray
    u_px: np.ndarray
    u_mm: np.ndarray
    noise_dn: np.ndarray  # the sensor noise estimated in each frame

    def csv_rows(self) -> list[str]:
        """``frame, t_s, s_mm, x_mm, y_mm, u_px, u_mm`` rows."""
        rows = []
        for f, frame in enumerate(self.frame):
            for m, s in enumerate(self.s_mm):
                x, y = self.mm[f, m]
                rows.append(
                    f"{frame},{self.t[f]:.9f},{s:g},{x:.5f},{y:.5f},{self.u_px[f, m]:.4f},{self.u_mm[f, m]:.5f}"
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
        inside = darkening[np.abs(darkening - centre) < 4 * sigma]
        centre, sigma = float(inside.mean()), float(inside.std())
    return sigma


def _blobs(
    darkening: np.ndarray, threshold: float, areas: tuple[float, float], noise: float
) -> tuple[np.ndarray, np.ndarray, list[int]]:
    # the marker-sized dark blobs' centres and uncertainties, and the areas of the others (px²)
    import cv2

    mask = (darkening > threshold).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    kernel = np.ones((2 * GROW_PX + 1, 2 * GROW_PX + 1), np.uint8)
    centres, sigmas, others = [], [], []
    for label in range(1, n):
        x0, y0, w, h, area = stats[label]
        if not areas[0] <= area <= areas[1]:
            others.append(int(area))
            continue
        r0, c0 = max(y0 - GROW_PX, 0), max(x0 - GROW_PX, 0)
        r1, c1 = min(y0 + h + GROW_PX, mask.shape[0]), min(x0 + w + GROW_PX, mask.shape[1])
        region = cv2.dilate((labels[r0:r1, c0:c1] == label).astype(np.uint8), kernel).astype(bool)
        weight = np.where(region, np.clip(darkening[r0:r1, c0:c1], 0, None), 0.0)
        rows, cols = np.mgrid[r0:r1, c0:c1]
        total = weight.sum()
        cx, cy = (weight * cols).sum() / total, (weight * rows).sum() / total
        spread = np.array([((cols - cx) ** 2)[region].sum(), ((rows - cy) ** 2)[region].sum()])
        centres.append((cx, cy))
        sigmas.append(noise * np.sqrt(spread) / total)
    return np.array(centres).reshape(-1, 2), np.array(sigmas).reshape(-1, 2), others


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
            f"{np.linalg.norm(plane[first] - start):.3g} mm away",
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


def track_markers(
    frames: Frames | FrameStream,
    background: np.ndarray,
    mapping: PlaneMapping,
    s_mm: np.ndarray,
    diameter_mm: float,
    path: str | Path,
    threshold_dn: float | None = None,
    progress: bool = False,
) -> Tracked:
    """Every marker in every frame (see the module docstring); ``frames`` gives
    ``(index, t, image)`` per frame, in memory or streamed."""
    from tqdm import tqdm

    path = Path(path)
    expected_area, *areas = _marker_areas(mapping, diameter_mm)
    index, t, px, sig, noise = [], [], [], [], []
    previous = np.zeros(2)  # the clamp's lowest point at rest
    bg = background.astype(np.float64)
    for i, time, image in tqdm(frames, total=frames.total, desc="tracking", unit=" frames", disable=not progress):
        darkening = bg - image
        noise.append(noise_sigma(darkening))
        threshold = threshold_dn if threshold_dn is not None else max(10.0 * noise[-1], 5.0)
        centres, sigmas, others = _blobs(darkening, threshold, tuple(areas), noise[-1])
        where = f"frame {i} (t = {time:.6g} s)"
        if not index and len(centres) < len(s_mm) / 2 and others:  # most missing: not one hidden marker
            raise ArgumentError(
                "diameter_mm",
                f"{diameter_mm:g} mm: {where} holds {len(centres)} blobs of a marker's area ({expected_area:.3g} px², "
                f"taken from {areas[0]:.3g} to {areas[1]:.3g}) for {len(s_mm)} markers, and {len(others)} dark blobs "
                f"of other areas (median {np.median(others):.3g} px², a disc of "
                f"{diameter_mm * np.sqrt(np.median(others) / expected_area):.3g} mm): give the markers' diameter",
            )
        plane = mapping.to_plane(centres) if len(centres) else centres
        # the first marker: near the clamp's lowest point at rest in the first frame, then
        # within half the spacing of where it was (it moves least: it is nearest the clamp)
        reach = 0.5 * (s_mm[1] - s_mm[0]) + (s_mm[0] if not index else 0.0)
        order = _chain(plane, previous, reach, s_mm, where, path)
        if not index:
            _check_first_marker(plane[order], s_mm, where)
        index.append(i)
        t.append(time)
        px.append(centres[order])
        sig.append(sigmas[order])
        previous = plane[order[0]]
    px, sig = np.array(px), np.array(sig)
    n, m = px.shape[:2]
    mm = mapping.to_plane(px.reshape(-1, 2)).reshape(n, m, 2)
    u_px = np.sqrt(0.5 * np.sum(sig**2, axis=2))
    u_mm = u_px * mapping.mm_per_px(px.reshape(-1, 2)).reshape(n, m)
    return Tracked(np.array(index), np.array(t), np.asarray(s_mm, dtype=float), px, mm, u_px, u_mm, np.array(noise))
