"""The strip's near edge, coloured as the seed paper colours it, found by its colour.

The paper dyes the fabric's near edge and films the strip from the side: a camera a few
degrees off square sees the edge (its cut face, the fabric's thickness wide) and a band of
the face behind it, and only the colour tells that band from a backdrop of the same
brightness. Each pixel's *colour signal* is its projection on the stated colour's chroma
(the colour less its grey, normalised), less the background's: neutral surfaces (a grey
backdrop, white fabric, a black clamp) give 0 whatever their brightness, a tinted backdrop
its tint, which the background's removes, the dyed band its saturation, and a pixel that
mixes the two gives the mixture's share, so the signal is linear in coverage, as the edge
locator needs (:mod:`.edges`).

The dyed band is the region of strong signal that reaches the clamp's lowest point at rest
(paths as in :mod:`.centreline`); across it, two passes find the band's centre (the
signal's centroid across), then its **silhouette**: the band's side on the backdrop (the
side where the frame matches the background; the other side is the undyed face), located
where the signal rises fastest from the backdrop into the band. That line is the edge's
outer surface, in the calibrated plane. With the fabric's thickness it is moved half of it
into the band, onto the midline the model's chain represents. Where the video keeps every
pixel's colour and the thickness is given, the cut face (the thickness wide, lit unlike the
dyed side face) is a step of its own in that fit and the free end is found along the
midline; a 4:2:0 video's colour (a sample per 2 × 2 pixels) cannot resolve it, and is
tracked without. Arc length is measured along the line from the free end, as the
centreline's is (s is the rest arc length only as far as the strip does not stretch).

Each point's uncertainty is given across the strip (the scatter of the silhouette about its
own smooth course: noise, compression, texture, reduced by the points averaged) and along
it (the free end's noise: its position moves every arc of the frame alike), each with the
floor validation measures: a curve's points (``u_along_mm``, :mod:`warpcloth.io.measured`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError, DataFileError

from .calibration import PlaneMapping
from .centreline import ARC_VALIDATED_PX, LINE_SMOOTH, _free_end, _region_path, _resample, normals, smooth_line
from .edges import band_edges, rising_edges, sample
from .markers import Tracked, noise_sigma
from .video import Frames, FrameStream

__all__ = ["chroma_direction", "colour_signal", "learn_edge_colour", "track_coloured_edge"]

SMOOTH_PX = 7  # the path's smoothing before normals are taken
PHASE_BLUR_PX = 1.0  # σ of the Gaussian the colour signal is smoothed with
ARC_WINDOW = 31  # px: the edge's smoothing before its arc is measured
VALIDATED_PX = 0.25
"""What the validation on video warpcloth did not render measures across the strip beyond
each point's noise (px; added to its uncertainty across in quadrature; along it
:data:`.centreline.ARC_VALIDATED_PX`): on the independent rig (scenes/data/rig/edge.mp4:
H.264 4:2:0, a dye band 0.5 + 0.65 mm wide whose cut face and side face differ in shade,
benchmarks/track_accuracy.py) the midline is off across by −0.021 mm (bias) and 0.050 mm
RMS, 0.24 px at 0.21 mm/px, where u covers 72 % within 1σ, 97 % within 2σ; on the
analytic frames of tests/test_track_edge.py by 0.01 mm (docs/calibration.md). On the rig's
frames recorded losslessly the midline is within 0.023 mm RMS and the same floor covers 96 %
within 1σ: kept for every video, conservative where the colour is at every pixel."""
ACROSS_HALF_WIDTHS = 3.0  # how far across the band each profile reaches, in half-widths, plus 3 px
END_INSET_HALF_WIDTHS = 3.0  # a profile across needs a whole band: the line starts this far inside the free end
LEAST_SATURATION = 0.08  # of the colour's brightness: a stated colour greyer than this has no chroma to track
FACE_RESOLVED_PX = 2.0
"""The narrowest cut face (the thickness, px) fitted as a step of its own: narrower, its step
and the silhouette's, each blurred by about 1.4 px, cannot be told apart (the edge then
scatters 0.13 px at 0.8 px against two steps' 0.03 px; 0.046 px at the rig's 2.4 px)."""


def chroma_direction(colour: np.ndarray) -> np.ndarray:
    """The unit vector in RGB of ``colour`` less its grey, or an error naming
    ``--edge-colour`` when the colour is (nearly) grey: its projection would not tell it
    from the backdrop."""
    colour = np.asarray(colour, dtype=float)
    chroma = colour - colour.mean()
    if np.linalg.norm(chroma) < LEAST_SATURATION * max(float(np.linalg.norm(colour)), 1e-9):
        raise ArgumentError(
            "--edge-colour",
            f"{','.join(f'{v:g}' for v in colour)} is grey (its colour less its grey is "
            f"{np.linalg.norm(chroma):.3g} of {np.linalg.norm(colour):.3g}): a grey edge cannot be told from the "
            "backdrop by its colour; give the dye's colour as R,G,B",
        )
    return chroma / np.linalg.norm(chroma)


def colour_signal(image: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Each pixel's projection on the chroma ``direction`` (an RGB image → a float image)."""
    return np.asarray(image, dtype=np.float64) @ direction


def learn_edge_colour(first: np.ndarray, background: np.ndarray, ignore: np.ndarray | None) -> np.ndarray:
    """The dye's colour from the first frame: the median colour of the most saturated tenth
    of the pixels that differ from the background (the strip, the clamp), an error when
    they hold no colour."""
    frame, bg = first.astype(np.float64), background.astype(np.float64)
    difference = np.abs(frame - bg).sum(axis=2)
    if ignore is not None:
        difference[ignore] = 0.0
    changed = difference > max(10.0 * noise_sigma(difference), 15.0)
    pixels = frame[changed]
    if len(pixels) < 20:
        raise ArgumentError(
            "--edge-colour", "auto: the first frame hardly differs from the background: no edge to learn"
        )
    saturation = np.linalg.norm(pixels - pixels.mean(axis=1, keepdims=True), axis=1)
    colour = np.median(pixels[saturation >= np.quantile(saturation, 0.9)], axis=0)
    chroma_direction(colour)  # refuses a grey one
    return colour


def _profile_across(
    signal: np.ndarray, line: np.ndarray, normal: np.ndarray, reach: float, samples: int
) -> tuple[np.ndarray, np.ndarray]:
    offsets = np.linspace(-reach, reach, samples)
    points = line[:, None, :] + offsets[None, :, None] * normal[:, None, :]
    return sample(signal, points), offsets


def _one_frame(
    signal: np.ndarray,
    luma_difference: np.ndarray,
    mapping: PlaneMapping,
    seed: np.ndarray,
    s_mm: np.ndarray,
    free_length_mm: float,
    thickness_mm: float | None,
    where: str,
    path: Path,
    full_chroma: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    # the edge's points (px) at s_mm, their σ across and along the strip (px) and the signal's noise
    import cv2

    noise = noise_sigma(signal)
    strong = signal > max(10.0 * noise, 5.0, 0.25 * float(np.quantile(signal, 0.999)))
    if strong.sum() < 20:
        raise DataFileError(path, f"{where}: no pixel holds the edge's colour (--edge-colour)")
    level = float(np.median(signal[strong]))
    mask = signal > 0.4 * level
    route = _region_path(mask, seed, where, path)
    inside = cv2.dilate(cv2.distanceTransform(mask.astype(np.uint8), cv2.DIST_L2, 5), np.ones((9, 9), np.uint8))
    half_width = max(float(np.median(inside[route[:, 1].astype(int), route[:, 0].astype(int)])), 1.0)
    line = smooth_line(_resample(route, 1.0), SMOOTH_PX)
    reach = ACROSS_HALF_WIDTHS * half_width + 3.0
    for _ in range(2):  # the band's centre: the signal's centroid across it, twice
        normal = normals(line)
        profile, offsets = _profile_across(signal, line, normal, reach, 97)
        weight = np.clip(profile - 0.5 * level, 0.0, None)
        shift = (weight * offsets).sum(axis=1) / np.maximum(weight.sum(axis=1), 1e-300)
        line = smooth_line(line + shift[:, None] * normal, SMOOTH_PX)
    normal = normals(line)
    inner = int(np.ceil(END_INSET_HALF_WIDTHS * half_width))
    if len(line) <= inner + LINE_SMOOTH:
        raise DataFileError(path, f"{where}: the coloured edge found is {len(line)} px long: too short to follow")
    # the backdrop's side: where, beyond the band, the frame is the background
    beyond = half_width + 3.0
    sides = [np.median(sample(luma_difference, line + sign * beyond * normal)) for sign in (1.0, -1.0)]
    side = 1.0 if sides[0] <= sides[1] else -1.0
    # from the backdrop across the band: its rise is the silhouette
    steps = np.linspace(reach, -half_width, 97)  # past the centre: the rise ends inside the band
    rising = sample(signal, line[:, None, :] + side * steps[None, :, None] * normal[:, None, :])
    at, _ = rising_edges(rising, 1.0, 0.3 * level)
    found = np.isfinite(at)
    if found.mean() < 0.8:
        raise DataFileError(
            path,
            f"{where}: the coloured edge's silhouette is found at {found.mean():.0%} of its points: the backdrop "
            "beside it is not neutral, or the edge is hidden (give --mask over what hides it)",
        )
    offset = np.interp(at, np.arange(len(steps)), steps)
    offset = np.where(found, offset, np.interp(np.arange(len(at)), np.flatnonzero(found), offset[found]))
    # then the band fitted across, both its sides at once (:func:`.edges.band_edges`): o runs
    # from the backdrop into the band, the silhouette at o = −offset
    o = np.linspace(-reach, reach, 97)
    points = line[:, None, :] - side * o[None, :, None] * normal[:, None, :]
    # the cut face, the thickness wide and lit unlike the dyed side face beside it, is a step
    # of its own where the colour is stored at every pixel; a 4:2:0 video's colour, a sample
    # per 2 × 2 pixels, cannot resolve it (the fit then scatters more than the step moves)
    thickness_px = None if thickness_mm is None else thickness_mm / mapping.mm_per_px(line)
    resolved = thickness_px is not None and full_chroma and np.median(thickness_px) >= FACE_RESOLVED_PX
    face = thickness_px if resolved else None
    silhouette, _, _, _ = band_edges(sample(signal, points), o, -offset, -offset + 2.0 * half_width, face=face)
    offset = np.where(np.abs(silhouette + offset) < half_width, -silhouette, offset)
    if thickness_px is not None:  # onto the midline, half the thickness inside the band
        offset = offset - 0.5 * thickness_px
    edge = line + side * offset[:, None] * normal
    # the scatter of the silhouette across the strip about its own smooth course
    course = np.convolve(np.pad(offset, 5, mode="edge"), np.ones(11) / 11, "valid")
    scatter_px = float(np.sqrt(np.mean((offset - course) ** 2)))
    # the free end along the midline, inside the cut face, where the colour resolves it: the
    # band's centre runs on the dyed side face, whose end recedes from the camera and is
    # seen short (0.05 mm on the rig); a 4:2:0 video's colour smears the midline's with the
    # backdrop's, so there the band's centre's end is moved across onto the midline
    along_midline = face is not None
    follow = edge[inner:] if along_midline else line[inner:]
    tip = _free_end(signal, follow, half_width)
    # the tip's uncertainty along the strip: the noise over the signal's slope where it crosses
    direction = (tip - follow[0]) / max(float(np.linalg.norm(tip - follow[0])), 1e-9)
    slope = (sample(signal, tip + 0.5 * direction) - sample(signal, tip - 0.5 * direction)).item()
    tip_px = noise / max(abs(slope), 1e-9)
    if not along_midline:
        tip = tip + side * offset[inner] * normal[inner]
    edge = edge[inner:]
    # a quadratic smoothing over ARC_WINDOW px: jitter across a line would lengthen its arc
    # (0.1 px every 5 px: 0.002 px per chord), a quadratic keeps the curve's bend
    from scipy.signal import savgol_filter

    window = min(ARC_WINDOW, len(edge) - (1 - len(edge) % 2))
    edge = savgol_filter(edge, window, 2, axis=0)[::5]
    line_px = np.vstack([tip, edge])
    line_mm = mapping.to_plane(line_px)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(line_mm, axis=0), axis=1))])
    wanted = free_length_mm - np.asarray(s_mm)
    if wanted.max() > arc[-1]:
        raise DataFileError(
            path,
            f"{where}: the coloured edge found is {arc[-1]:.3g} mm long from the free end, shorter than the "
            f"{wanted.max():g} mm to s = {np.min(s_mm):g} mm (--edge-s, --free-length-mm; or the clamp hides its "
            "root: start --edge-s further down, or give --background, a frame without the strip, if the median "
            "of the frames holds the clamp turned)",
        )
    points = np.column_stack([np.interp(wanted, arc, line_px[:, 0]), np.interp(wanted, arc, line_px[:, 1])])
    # across: the silhouette's scatter about its course, averaged over LINE_SMOOTH px at
    # least; along: the free end's, which every arc measured from it carries; each with
    # what the validation measures beyond it
    across = np.full(len(points), np.hypot(scatter_px / np.sqrt(LINE_SMOOTH), VALIDATED_PX))
    return points, across, np.full(len(points), np.hypot(tip_px, ARC_VALIDATED_PX)), noise


def track_coloured_edge(
    frames: Frames | FrameStream,
    background: np.ndarray,
    mapping: PlaneMapping,
    s_mm: np.ndarray,
    free_length_mm: float,
    colour: np.ndarray | None,
    path: str | Path,
    thickness_mm: float | None = None,
    ignore: np.ndarray | None = None,
    progress: bool = False,
) -> Tracked:
    """The coloured near edge at arc lengths ``s_mm`` from the clamp's lowest point in every
    frame of an RGB video (see the module docstring); ``colour`` (RGB, 0–255) the dye's, or
    None to learn it from the first frame."""
    import cv2
    from tqdm import tqdm

    path = Path(path)
    seed = mapping.to_pixels(np.zeros((1, 2)))[0]
    bg = np.asarray(background, dtype=np.float64)
    bg_luma = bg @ [0.299, 0.587, 0.114]
    direction = None if colour is None else chroma_direction(colour)
    index, t, px, u, u_along, noise = [], [], [], [], [], []
    for i, time, image in tqdm(
        frames, total=frames.total, desc="tracking the coloured edge", unit=" frames", disable=not progress
    ):
        if direction is None:
            colour = learn_edge_colour(image, background, ignore)
            direction = chroma_direction(colour)
        # blurred by a pixel: chroma stored at half resolution (4:2:0) and interpolated back
        # is piecewise linear, whose edge shape would move with the edge's pixel phase
        # less the background's own: a warm-lit backdrop has some of the dye's chroma too
        signal = cv2.GaussianBlur(colour_signal(image, direction) - colour_signal(bg, direction), (0, 0), PHASE_BLUR_PX)
        if ignore is not None:
            signal[ignore] = 0.0
        luma = np.asarray(image, dtype=np.float64) @ [0.299, 0.587, 0.114]
        points, sigma, sigma_along, frame_noise = _one_frame(
            signal,
            np.abs(luma - bg_luma),
            mapping,
            seed,
            s_mm,
            free_length_mm,
            thickness_mm,
            f"frame {i} (t = {time:.6g} s)",
            path,
            frames.chroma_subsampling == (1, 1),
        )
        index.append(i)
        t.append(time)
        px.append(points)
        u.append(sigma)
        u_along.append(sigma_along)
        noise.append(frame_noise)
    return Tracked.in_plane(mapping, index, t, s_mm, np.array(px), np.array(u), noise, np.array(u_along))
