"""The synthetic camera: warpcloth's own simulation filmed, to check the tracker against.

    python -m warpcloth.track.render [OUT_DIR]     # default: scenes/data/track/

renders the bundled example the tracker is tested on: the impulsive rotation (rotation
centre 4.0 mm above the clamp's lowest point, γ = 0.8 /s) simulated by warpcloth at
h = 0.625 mm (4× finer than the scene a fit runs, as a lab's strip is the continuum), its
strip seen edge on with dark dots on it, filmed at 60 frames/s by a camera that is *not*
square to the strip's plane (tilted 20° and 12°), with lens distortion (k1 = −0.25,
k2 = 0.12, p1, p2), uneven lighting (a gradient and vignetting), motion blur (each frame
the mean of 6 instants across a 1 ms exposure), a Gaussian optical blur (σ 0.5 px),
sensor noise (σ 1.0 DN) and 8-bit quantisation, about 0.2 mm per pixel; and, by the
same camera, images of a chessboard (12 × 11 squares of 10 mm) in several poses, one of
them held in the strip's plane with an inner corner at the clamp's lowest point.

Image formation is integrated, not point-sampled: each pixel averages 3 × 3 rays, each ray
is traced through this module's own NumPy camera model (:mod:`warpcloth.track.camera`,
not OpenCV's) to the plane, and reads a texture drawn at 0.05 mm per texel (the markers'
edges by exact analytic coverage). The truth is the simulation's marker positions at each
frame's timestamp (the middle of its exposure).
"""

from __future__ import annotations

import sys
from fractions import Fraction
from pathlib import Path

import numpy as np

from warpcloth.errors import InternalError
from warpcloth.io.json_file import json_text

from .camera import Camera, PlanePose, rotation

__all__ = ["EXAMPLE", "make_example"]

EXAMPLE = {
    "truth": {"clamp.rotation_centre_dy_mm": 4.0, "damping.gamma_per_s": 0.8},
    "spacing_mm": 0.625,
    "duration_s": 0.25,
    "frame_rate_hz": 60,
    "exposure_s": 1e-3,
    "instants_per_exposure": 6,
    "marker_s_mm": [5.0 + 10.0 * i for i in range(10)],
    "marker_diameter_mm": 2.4,
    "strip_thickness_mm": 1.6,
    "board_squares": [12, 11],
    "square_mm": 10.0,
    "origin_corner": [1, 1],
    "noise_dn": 1.0,
    "optical_blur_px": 0.5,
    "seed": 24,
}
"""What the bundled example is made of."""

CAMERA = Camera(
    fx=2300.0, fy=2300.0, cx=383.2, cy=357.6, distortion=(-0.25, 0.12, 6e-4, -4e-4, 0.0), width=768, height=720
)
STRIP_PLANE = PlanePose(rotation(-12.0, 20.0, 1.5), np.zeros(3))
SUPERSAMPLE = 3
TEXEL_MM = 0.05
ALBEDO = {"wall": 0.45, "strip": 0.85, "marker": 0.05, "clamp": 0.75, "black": 0.08, "white": 0.85}
WALL_BOX_MM = (-40.0, -40.0, 140.0, 140.0)  # X0, Y0, X1, Y1 of the strip plane's texture (Y = −y, down)
BOARD_MARGIN_MM = 8.0
BOARD_VIEWS = [  # (about x, about y, about z) degrees, centre offset (mm, camera frame), distance (mm)
    ((0.0, 0.0, 0.0), (0.0, 0.0), 560.0),
    ((-25.0, 5.0, 4.0), (-18.0, -14.0), 540.0),
    ((22.0, -8.0, -6.0), (16.0, 14.0), 560.0),
    ((5.0, 28.0, 10.0), (-20.0, 16.0), 560.0),
    ((-8.0, -26.0, -12.0), (20.0, -16.0), 550.0),
]


def _place_strip_plane() -> PlanePose:
    # the strip plane's point (x, y) = (45, −40) mm, the middle of the motion, on the optical
    # axis 460 mm away; plane coordinates (X, Y) = (x, −y)
    centre = STRIP_PLANE.rotation @ np.array([45.0, 40.0, 0.0])
    return PlanePose(STRIP_PLANE.rotation, np.array([0.0, 0.0, 460.0]) - centre)


def _ray_grid(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    # normalised coordinates of the SUPERSAMPLE² rays of every pixel (pixel centres are integers)
    sub = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    u = (np.arange(camera.width)[:, None] + sub).ravel()
    v = (np.arange(camera.height)[:, None] + sub).ravel()
    uu, vv = np.meshgrid(u, v)
    x, y = camera.rays(uu, vv)
    back = camera.project(np.stack([x, y, np.ones_like(x)], axis=-1))
    worst = float(np.max(np.abs(back - np.stack([uu, vv], axis=-1))))
    if worst > 1e-6:
        raise InternalError(
            f"the camera model's inverse is off by {worst:g} px: a bug in warpcloth's camera model, please report it"
        )
    return x, y


def _texture_map(
    camera_rays: tuple[np.ndarray, np.ndarray], pose: PlanePose, box: tuple[float, float, float, float]
) -> tuple[np.ndarray, np.ndarray]:
    # for cv2.remap: the texel (column, row) every ray reads, texel centres at integers
    px, py = pose.from_rays(*camera_rays)
    return (((px - box[0]) / TEXEL_MM - 0.5).astype(np.float32), ((py - box[1]) / TEXEL_MM - 0.5).astype(np.float32))


def _integrate(texture: np.ndarray, maps: tuple[np.ndarray, np.ndarray], border: float) -> np.ndarray:
    import cv2

    rays = cv2.remap(texture, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=border)
    h, w = rays.shape[0] // SUPERSAMPLE, rays.shape[1] // SUPERSAMPLE
    return rays.reshape(h, SUPERSAMPLE, w, SUPERSAMPLE).mean(axis=(1, 3))


def _lighting(camera: Camera) -> np.ndarray:
    # a left-to-right gradient and a vignette: 0.62 to 1.08 across the image
    v, u = np.mgrid[0 : camera.height, 0 : camera.width].astype(float)
    r2 = ((u - camera.cx) ** 2 + (v - camera.cy) ** 2) / (0.5 * camera.width) ** 2
    return 0.8 + 0.28 * (u / camera.width) - 0.12 * r2 - 0.06 * (v / camera.height)


def _expose(radiance: np.ndarray, lighting: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    import cv2

    signal = cv2.GaussianBlur(255.0 * lighting * radiance, (0, 0), EXAMPLE["optical_blur_px"])
    noisy = signal + rng.normal(0.0, EXAMPLE["noise_dn"], signal.shape)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def _wall(rng: np.random.Generator) -> np.ndarray:
    # the strip plane's background: the wall's albedo with a smooth ±12 % pattern
    import cv2

    x0, y0, x1, y1 = WALL_BOX_MM
    shape = (round((y1 - y0) / TEXEL_MM), round((x1 - x0) / TEXEL_MM))
    pattern = cv2.resize(rng.uniform(-1, 1, (12, 12)).astype(np.float32), shape[::-1], interpolation=cv2.INTER_CUBIC)
    return (ALBEDO["wall"] * (1 + 0.12 * pattern)).astype(np.float32)


def _texel(x_mm: np.ndarray, y_down_mm: np.ndarray) -> np.ndarray:
    x0, y0 = WALL_BOX_MM[:2]
    return np.stack([(x_mm - x0) / TEXEL_MM - 0.5, (y_down_mm - y0) / TEXEL_MM - 0.5], axis=-1)


def _draw_band(texture: np.ndarray, free: np.ndarray, half: float) -> None:
    # the strip's edge: a band of its thickness along the free nodes, cut square at both ends,
    # its edges by exact coverage (OpenCV's anti-aliased fill grows a shape by ~1.5 texels,
    # and a thick polyline's round caps would lengthen the strip by half its thickness)
    import cv2

    candidates = np.zeros(texture.shape, np.uint8)
    pts = np.rint(_texel(free[:, 0], -free[:, 1])).astype(np.int32)
    cv2.polylines(candidates, [pts], False, 1, int(2 * half / TEXEL_MM) + 6)
    rows, cols = np.nonzero(candidates)
    x0, y0 = WALL_BOX_MM[:2]
    point = np.column_stack([x0 + (cols + 0.5) * TEXEL_MM, -(y0 + (rows + 0.5) * TEXEL_MM)])  # mm, y up
    a, b = free[:-1], free[1:]
    ab = b - a
    w = np.clip(((point[:, None] - a) * ab).sum(axis=2) / (ab * ab).sum(axis=1), 0, 1)
    distance = np.min(np.linalg.norm(point[:, None] - (a + w[..., None] * ab), axis=2), axis=1)
    side = np.clip((half - distance) / TEXEL_MM + 0.5, 0, 1)
    end_tangent = ab[-1] / np.linalg.norm(ab[-1])
    start_tangent = ab[0] / np.linalg.norm(ab[0])
    beyond = np.clip(0.5 - ((point - free[-1]) @ end_tangent) / TEXEL_MM, 0, 1)
    before = np.clip(0.5 - ((free[0] - point) @ start_tangent) / TEXEL_MM, 0, 1)
    coverage = (side * beyond * before).astype(np.float32)
    texture[rows, cols] += (ALBEDO["strip"] - texture[rows, cols]) * coverage


def _draw_strip(wall: np.ndarray, nodes_mm: np.ndarray, n_clamped: int, markers_mm: np.ndarray) -> np.ndarray:
    """The wall with the clamp, the strip's edge and its markers drawn at one instant
    (nodes and markers in the clamp-edge frame, mm, y up)."""
    import cv2

    texture = wall.copy()
    shift = 4
    scale = 2**shift
    cover = np.zeros(texture.shape, np.uint8)
    # the clamp: a bar 8 mm wide along the clamped nodes, 4 mm past the top one (its edges
    # are not measured: OpenCV's anti-aliased fill does)
    top, low = nodes_mm[0], nodes_mm[n_clamped - 1]
    along = (top - low) / np.linalg.norm(top - low)
    across = np.array([-along[1], along[0]]) * 4.0
    end = top + 4.0 * along
    corners = np.array([low + across, low - across, end - across, end + across])
    pts = np.rint(_texel(corners[:, 0], -corners[:, 1]) * scale).astype(np.int32)
    cv2.fillPoly(cover, [pts], 255, cv2.LINE_AA, shift)
    texture += (ALBEDO["clamp"] - texture) * (cover / 255.0)
    _draw_band(texture, nodes_mm[n_clamped - 1 :], 0.5 * EXAMPLE["strip_thickness_mm"])
    radius = 0.5 * EXAMPLE["marker_diameter_mm"] / TEXEL_MM
    for centre in _texel(markers_mm[:, 0], -markers_mm[:, 1]):
        c0, r0 = np.floor(centre - radius - 2).astype(int)
        c1, r1 = np.ceil(centre + radius + 2).astype(int)
        rows, cols = np.mgrid[r0 : r1 + 1, c0 : c1 + 1]
        # exact area coverage of a disc edge, to first order: a one-texel linear ramp
        coverage = np.clip(radius - np.hypot(cols - centre[0], rows - centre[1]) + 0.5, 0, 1)
        patch = texture[r0 : r1 + 1, c0 : c1 + 1]
        patch += (ALBEDO["marker"] - patch) * coverage.astype(np.float32)
    return texture


def _board_texture() -> tuple[np.ndarray, tuple[float, float, float, float]]:
    # board coordinates (X, Y) mm with inner corner (0, 0) at the origin, X along a row
    nx, ny = EXAMPLE["board_squares"]
    sq = EXAMPLE["square_mm"]
    edge = sq + BOARD_MARGIN_MM
    box = (-edge, -edge, (nx - 2) * sq + edge, (ny - 2) * sq + edge)
    shape = (round((box[3] - box[1]) / TEXEL_MM), round((box[2] - box[0]) / TEXEL_MM))
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    x, y = box[0] + (cols + 0.5) * TEXEL_MM, box[1] + (rows + 0.5) * TEXEL_MM
    i, j = np.floor((x + sq) / sq), np.floor((y + sq) / sq)
    inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
    texture = np.where(inside, np.where((i + j) % 2 == 0, ALBEDO["black"], ALBEDO["white"]), ALBEDO["white"])
    return texture.astype(np.float32), box


def _board_views(strip_plane: PlanePose) -> list[PlanePose]:
    nx, ny = EXAMPLE["board_squares"]
    sq = EXAMPLE["square_mm"]
    middle = np.array([(nx - 2) * sq / 2, (ny - 2) * sq / 2, 0.0])
    views = []
    for angles, offset, distance in BOARD_VIEWS:
        r = rotation(*angles)
        views.append(PlanePose(r, np.array([offset[0], offset[1], distance]) - r @ middle))
    # the plane view: the board in the strip's plane, inner corner `origin_corner` at the
    # clamp's lowest point, its rows level (board X = x, board Y = −y)
    ci, cj = EXAMPLE["origin_corner"]
    return [strip_plane.shifted((-ci * sq, -cj * sq)), *views]


def _truth_run() -> tuple[object, object]:
    import copy

    from warpcloth.runs import simulate
    from warpcloth.scene import read_scene_file, scene_from_dict, set_field

    data = read_scene_file("impulsive_rotation")
    fields = EXAMPLE["truth"] | {
        "strip.spacing_mm": EXAMPLE["spacing_mm"],  # 4× finer than the scene's: the continuum, as a lab films
        "integrator.scheme": "imex",
        "integrator.dt_s": "auto",
        "run.duration_s": EXAMPLE["duration_s"] + 0.01,
        "output.frame_rate_hz": 6000.0,
        "output.probes_per_frame": 1,
    }
    for key, value in fields.items():
        set_field(data, key, value)
    scene = scene_from_dict(copy.deepcopy(data))
    return scene, simulate(scene)


def _at(result: object, t: float) -> np.ndarray:
    # node positions (mm, clamp-edge frame) at time t, linear between 1/6000 s frames
    ft = result.frame_times
    k = int(np.clip(np.searchsorted(ft, t) - 1, 0, len(ft) - 2))
    w = (t - ft[k]) / (ft[k + 1] - ft[k])
    return (result.frames[k, 0] * (1 - w) + result.frames[k + 1, 0] * w) * 1e3


def _markers(nodes_mm: np.ndarray, scene: object, s_mm: np.ndarray) -> np.ndarray:
    arc = s_mm / scene.strip.spacing_mm + scene.n_clamped - 1
    node = np.floor(arc).astype(int)
    w = (arc - node)[:, None]
    return nodes_mm[node] * (1 - w) + nodes_mm[np.minimum(node + 1, len(nodes_mm) - 1)] * w


def make_example(out: str | Path, progress: bool = True) -> dict:
    """Render the bundled example into ``out``: ``rotation.avi`` (FFV1, lossless),
    ``background.png``, ``board_0.png`` (the plane view) … ``board_5.png``,
    ``truth.csv`` (the simulated markers at each frame's time) and ``truth.json``."""
    import cv2
    from tqdm import tqdm

    from warpcloth.io.atomic import write_atomically, write_text_atomically

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(EXAMPLE["seed"])
    rays = _ray_grid(CAMERA)
    lighting = _lighting(CAMERA)
    strip_plane = _place_strip_plane()
    board, board_box = _board_texture()
    for i, pose in enumerate(_board_views(strip_plane)):
        image = _expose(_integrate(board, _texture_map(rays, pose, board_box), ALBEDO["wall"]), lighting, rng)
        write_atomically(out / f"board_{i}.png", lambda tmp, image=image: cv2.imwrite(str(tmp), image))
    wall = _wall(rng)
    wall_maps = _texture_map(rays, strip_plane, WALL_BOX_MM)
    background = _expose(_integrate(wall, wall_maps, ALBEDO["wall"]), lighting, rng)
    write_atomically(out / "background.png", lambda tmp: cv2.imwrite(str(tmp), background))
    scene, result = _truth_run()
    rate = EXAMPLE["frame_rate_hz"]
    n_frames = round(EXAMPLE["duration_s"] * rate) + 1
    s_mm = np.array(EXAMPLE["marker_s_mm"])
    offsets = (np.arange(EXAMPLE["instants_per_exposure"]) + 0.5) / EXAMPLE["instants_per_exposure"] - 0.5
    images, rows = [], []
    for k in tqdm(range(n_frames), desc="rendering frames", unit=" frames", disable=not progress):
        t = k / rate
        radiance = np.zeros((CAMERA.height, CAMERA.width))
        for offset in offsets:
            instant = max(t + offset * EXAMPLE["exposure_s"], 0.0)  # at rest before t = 0
            nodes = _at(result, instant)
            radiance += _integrate(
                _draw_strip(wall, nodes, scene.n_clamped, _markers(nodes, scene, s_mm)), wall_maps, ALBEDO["wall"]
            )
        images.append(_expose(radiance / len(offsets), lighting, rng))
        truth = _markers(_at(result, t), scene, s_mm)
        rows += [f"{k},{t:.9f},{s:g},{x:.6f},{y:.6f}" for s, (x, y) in zip(s_mm, truth, strict=True)]
    from .video import read_frames, write_video

    write_atomically(out / "rotation.avi", lambda tmp: write_video(tmp, images, range(n_frames), Fraction(1, rate)))
    back = read_frames(out / "rotation.avi")
    if not (np.array_equal(back.images, np.stack(images)) and np.array_equal(back.t, np.arange(n_frames) / rate)):
        raise InternalError(
            "the video does not read back as written (lossless, exact timestamps): a bug in warpcloth or in "
            "its video library (PyAV, FFmpeg), please report it"
        )
    write_text_atomically(
        out / "truth.csv",
        "# the simulated markers at each frame's time (python -m "
        f"warpcloth.track.render; truth {EXAMPLE['truth']})\nframe,t_s,s_mm,x_mm,y_mm\n" + "\n".join(rows) + "\n",
    )
    described = {
        "example": EXAMPLE,
        "camera": {
            "matrix": CAMERA.matrix.tolist(),
            "distortion": CAMERA.distortion,
            "image_size_px": [CAMERA.width, CAMERA.height],
        },
        "strip_plane": {"rotation": strip_plane.rotation.tolist(), "translation_mm": strip_plane.translation.tolist()},
        "files": {
            "video": "rotation.avi (FFV1 in AVI, lossless, 8-bit grey)",
            "background": "background.png",
            "plane_view": "board_0.png",
            "boards": [f"board_{i}.png" for i in range(len(BOARD_VIEWS) + 1)],
            "truth": "truth.csv",
        },
    }
    write_text_atomically(out / "truth.json", json_text(described) + "\n")
    return described


if __name__ == "__main__":
    import importlib.resources

    # by default the bundled example itself (scenes/data/track/ of a checkout or an editable install)
    make_example(
        sys.argv[1]
        if len(sys.argv) > 1
        else Path(str(importlib.resources.files("warpcloth.scenes"))) / "data" / "track"
    )
