"""An independent synthetic lab rig: warpcloth's own simulation of the impulsive rotation of
a clamped fabric strip, filmed in 3D through a camera that shares nothing with the tracker.

Why. The tracker (``warpcloth track``) calibrates the OpenCV Brown–Conrady camera model
with a chessboard and assumes the strip is a curve in the calibration plane. Video from
warpcloth's own renderer (:mod:`warpcloth.track.render`) uses that very camera model and a
flat band in that very plane, so it checks only self-consistency. This module films the
same kind of experiment the way a real rig would, written from scratch in NumPy, and
writes the files the tracker is tested on.

What is modelled (world frame in mm: x right, y up, z towards the camera; the origin is
the clamp's lowest point at rest):

* The truth: :func:`warpcloth.runs.simulate` of ``impulsive_rotation`` (rotation centre
  2.8 mm above the clamp's lowest point, damping 0.4 /s, 0.625 mm spacing, frames at
  6000 /s), node positions interpolated linearly in time.
* The strip is a solid fabric of thickness ``t`` = 0.5 mm and width ``W`` = 25 mm: its
  cross-section in (x, y) is the band of half-width t/2 about the midline polyline of the
  free nodes (node offsets along the bisecting node normals, linear between nodes, cut
  square at the free end), extruded from z = 0 (the near edge, facing the camera) to
  z = -W. Rays are cast exactly against this prism: the near-edge cap, both side walls
  and the free-end cap; the nearest hit wins. Seen obliquely, the near edge shows with
  one side face receding in depth.
* Markers are matt dark discs (albedo 0.05, 2.4 mm across) in the plane z = +0.05 mm,
  centred on the midline at s = 5, 15, ..., 95 mm: they overhang the near edge on both
  sides. The "edge" variant has no markers; its near edge is dyed red instead (the cap
  and the side walls for -2 mm <= z <= 0).
* The clamp is a dark anodised block (24 x 12 x W + 12 mm) moving rigidly with the
  simulation's clamped nodes, with two domed steel screw heads (slotted, specular) on its
  front face; it occludes what is behind it.
* The backdrop is the plane z = -90 mm with a multi-scale random albedo texture and fine
  grain; lighting is Lambert with one directional light plus ambient, modulated by a
  smooth world-space falloff (a lamp's pool of light).
* The camera is a Kannala–Brandt (equidistant fisheye family) lens,
  r = f (theta + k1 theta^3 + k2 theta^5), with a principal point off centre and
  fy = 1.003 fx, posed 19 degrees from square about the vertical, with pitch and roll.
  It is not OpenCV's model; OpenCV's k1, k2, p1, p2, k3 fits it to well under 0.1 px.
* Image formation: 3 x 3 rays per pixel (5 x 5 for the boards), motion blur over a 4 ms exposure (at least 8
  instants, more so that nothing moves more than 0.5 px between instants), Gaussian
  optical blur, vignetting, shot-like noise, 8-bit RGB, H.264 in MP4.

Independence: nothing here imports or mirrors :mod:`warpcloth.track.camera`,
:mod:`~warpcloth.track.render`, :mod:`~warpcloth.track.markers` or
:mod:`~warpcloth.track.centreline`; OpenCV and PyAV are used only for image I/O, the
optical blur and encoding, never for a camera model or projection.

Run ``python -m warpcloth.track.rig [OUT_DIR]``; OUT_DIR defaults to
``scenes/data/rig/`` in the checkout.
"""

from __future__ import annotations

import copy
import importlib.resources
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from warpcloth.errors import InternalError
from warpcloth.io.atomic import write_atomically, write_text_atomically

__all__ = [
    "BOARD_INNER",
    "BOARD_SQUARE_MM",
    "MARKER_S_MM",
    "KannalaBrandtLens",
    "Motion",
    "Rig",
    "RigCamera",
    "main",
    "rig_camera",
    "simulate_motion",
]

# ---------------------------------------------------------------- the rig's dimensions (mm)
DURATION_S = 0.4
"""Filmed span: frames at 60 /s from t = 0 to this time inclusive."""
FPS = 60
SIM_RATE_HZ = 6000.0
TRUTH = {"clamp.rotation_centre_dy_mm": 2.8, "damping.gamma_per_s": 0.4}
"""The simulation parameters a fit of the tracked video should recover."""
THICKNESS_MM = 0.5
WIDTH_MM = 25.0
MARKER_S_MM = np.arange(5.0, 96.0, 10.0)
"""Marker arc lengths from the clamp's lowest point (mm)."""
MARKER_DIAMETER_MM = 2.4
MARKER_Z_MM = 0.05
MARKER_ALBEDO = 0.05
FABRIC_ALBEDO = np.array([0.80, 0.80, 0.78])
DYE_ALBEDO = np.array([0.75, 0.08, 0.08])
DYE_DEPTH_MM = 2.0
CLAMP_SIZE_MM = (24.0, 12.0)  # along its lowest line, along the strip (up)
CLAMP_Z_MM = (-WIDTH_MM - 6.0, 6.0)
CLAMP_ALBEDO = np.array([0.060, 0.068, 0.085])
SCREW_CENTRES_MM = ((-6.0, 6.0), (6.0, 6.0))  # (u, v) on the clamp's front face
SCREW_SLOT_ANGLES = (0.5, -0.9)  # rad, in the clamp's frame
SCREW_RADIUS_MM = 2.0
SCREW_DOME_RADIUS_MM = 3.0
SCREW_ALBEDO = 0.8
BACKDROP_Z_MM = -90.0
BACKDROP_TINT = np.array([1.0, 0.96, 0.90])
BOARD_INNER = (11, 10)
"""Inner corners of the chessboard (columns, rows): 12 x 11 squares."""
BOARD_SQUARE_MM = 10.0
BOARD_MARGIN_MM = 10.0
BOARD_ALBEDO = (0.08, 0.85)

# ------------------------------------------------------------------------ light and sensor
LIGHT_DIR = np.array([0.45, 0.55, 0.70]) / np.linalg.norm([0.45, 0.55, 0.70])
AMBIENT = 0.35
DIFFUSE = 0.65
POOL_CENTRE_MM = (-60.0, 60.0)
POOL_SIGMA_MM = 220.0
GAIN_DN = 280.0
"""Digital number per unit radiance (albedo 1 fully lit)."""
EXPOSURE_S = 0.004
MIN_INSTANTS = 8
MAX_STEP_PX = 0.5
OPTICAL_BLUR_PX = 0.6
VIGNETTE = (0.20, 0.05)  # relative darkening at the image corner: r^2 and r^4 terms
READ_NOISE_DN = 0.6
SHOT_NOISE_DN2_PER_DN = (1.5**2 - 0.6**2) / 120.0  # sigma = 1.5 DN at 120 DN
SUPERSAMPLE = 3
BOARD_SUPERSAMPLE = 5
SEED = 20240611
WIDTH_PX, HEIGHT_PX = 768, 720


# ============================================================================ the camera
@dataclass(frozen=True)
class KannalaBrandtLens:
    """An equidistant-fisheye-family lens: a ray at angle ``theta`` from the optical axis
    lands at distance ``d(theta) = theta + k1 theta^3 + k2 theta^5`` (in focal lengths)
    from the principal point, along the ray's azimuth; pixels are ``fx`` by ``fy``."""

    fx: float
    fy: float
    cx: float
    cy: float
    k1: float
    k2: float

    def radius(self, theta: np.ndarray) -> np.ndarray:
        """The image radius in focal lengths at angle ``theta`` (rad) from the axis."""
        t2 = theta * theta
        return theta * (1.0 + t2 * (self.k1 + t2 * self.k2))

    def project(self, directions: np.ndarray) -> np.ndarray:
        """Camera-frame directions ``[n, 3]`` (x right, y down, z forward) → pixels ``[n, 2]``
        (pixel centres at integers)."""
        d = np.asarray(directions, dtype=np.float64)
        rho = np.hypot(d[:, 0], d[:, 1])
        theta = np.arctan2(rho, d[:, 2])
        scale = np.divide(self.radius(theta), rho, out=np.ones_like(rho), where=rho > 0)
        return np.column_stack([self.cx + self.fx * scale * d[:, 0], self.cy + self.fy * scale * d[:, 1]])

    def unproject(self, pixels: np.ndarray) -> np.ndarray:
        """Pixels ``[n, 2]`` → unit camera-frame directions ``[n, 3]`` (Newton on ``d(theta)``)."""
        p = np.asarray(pixels, dtype=np.float64)
        a = (p[:, 0] - self.cx) / self.fx
        b = (p[:, 1] - self.cy) / self.fy
        r = np.hypot(a, b)
        theta = r.copy()
        for _ in range(8):
            t2 = theta * theta
            theta -= (self.radius(theta) - r) / (1.0 + t2 * (3.0 * self.k1 + 5.0 * self.k2 * t2))
        sin_t = np.sin(theta)
        scale = np.divide(sin_t, r, out=np.ones_like(r), where=r > 0)
        return np.column_stack([a * scale, b * scale, np.cos(theta)])


@dataclass(frozen=True)
class RigCamera:
    """A central camera: centre (world mm), rotation (rows: the camera's x right, y down
    and z forward axes in world coordinates), lens and image size."""

    lens: KannalaBrandtLens
    centre: np.ndarray
    rotation: np.ndarray
    width: int = WIDTH_PX
    height: int = HEIGHT_PX
    pose: dict = field(default_factory=dict)

    def project(self, points: np.ndarray) -> np.ndarray:
        """World points ``[n, 3]`` (mm) → pixels ``[n, 2]``."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return self.lens.project((pts - self.centre) @ self.rotation.T)

    def rays(self, pixels: np.ndarray) -> np.ndarray:
        """Pixels ``[n, 2]`` → unit world ray directions ``[n, 3]`` from :attr:`centre`."""
        return self.lens.unproject(pixels) @ self.rotation

    def depth(self, points: np.ndarray) -> np.ndarray:
        """Distance along the optical axis of world points ``[n, 3]`` (mm)."""
        return (np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.centre) @ self.rotation[2]


def rig_camera(
    yaw_deg: float = 19.0,
    pitch_deg: float = 4.0,
    roll_deg: float = 1.5,
    distance_mm: float = 450.0,
    target_mm: Sequence[float] = (30.0, -42.0, 0.0),
) -> RigCamera:
    """The rig's camera: its optical axis through ``target_mm`` from ``distance_mm`` away,
    turned ``yaw_deg`` about the vertical towards +x (so the strip's +x side face shows),
    raised ``pitch_deg`` (looking down), then rolled ``roll_deg`` about the axis."""
    lens = KannalaBrandtLens(
        fx=2250.0, fy=2250.0 * 1.003, cx=WIDTH_PX / 2 + 3.7, cy=HEIGHT_PX / 2 - 2.9, k1=0.12, k2=0.3
    )
    yaw, pitch, roll = np.radians([yaw_deg, pitch_deg, roll_deg])
    target = np.asarray(target_mm, dtype=np.float64)
    back = np.array([np.sin(yaw) * np.cos(pitch), np.sin(pitch), np.cos(yaw) * np.cos(pitch)])
    centre = target + distance_mm * back
    forward = -back
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    c, s = np.cos(roll), np.sin(roll)
    right, down = c * right + s * down, -s * right + c * down
    rotation = np.vstack([right, down, forward])
    pose = {
        "yaw_deg": yaw_deg,
        "pitch_deg": pitch_deg,
        "roll_deg": roll_deg,
        "distance_mm": distance_mm,
        "target_mm": target.tolist(),
        "optical_axis_to_plane_normal_deg": float(np.degrees(np.arccos(back[2]))),
    }
    return RigCamera(lens=lens, centre=centre, rotation=rotation, pose=pose)


# ========================================================================= the truth
@dataclass
class Motion:
    """The simulated strip: node positions ``nodes_mm[k, node, 2]`` at ``times_s[k]``, the
    first ``n_clamped`` nodes in the clamp; before the first time the strip is at rest."""

    times_s: np.ndarray
    nodes_mm: np.ndarray
    n_clamped: int
    spacing_mm: float
    free_length_mm: float
    description: dict

    def nodes_at(self, t: float) -> np.ndarray:
        """All node positions (mm) at time ``t`` (s), linear between simulated frames."""
        times = self.times_s
        if t <= times[0]:
            return self.nodes_mm[0].copy()
        if t >= times[-1]:
            return self.nodes_mm[-1].copy()
        i = int(np.searchsorted(times, t, side="right")) - 1
        w = (t - times[i]) / (times[i + 1] - times[i])
        return (1.0 - w) * self.nodes_mm[i] + w * self.nodes_mm[i + 1]

    def free(self, nodes: np.ndarray) -> np.ndarray:
        """The free strip's nodes, from the clamp's lowest point to the free end."""
        return nodes[self.n_clamped - 1 :]

    def midline(self, nodes: np.ndarray, s_mm: np.ndarray) -> np.ndarray:
        """Midline points ``[n, 2]`` at arc lengths ``s_mm`` from the clamp's lowest point."""
        free = self.free(nodes)
        f = np.asarray(s_mm, dtype=np.float64) / self.spacing_mm
        i = np.clip(np.floor(f).astype(int), 0, len(free) - 2)
        w = (f - i)[:, None]
        return (1.0 - w) * free[i] + w * free[i + 1]


def simulate_motion(duration_s: float = DURATION_S) -> Motion:
    """Simulate the impulsive rotation with warpcloth (the truth), frames at 6000 /s."""
    from warpcloth.runs import simulate
    from warpcloth.scene import read_scene_file, scene_from_dict, set_field

    data = read_scene_file("impulsive_rotation")
    settings = {
        **TRUTH,
        "strip.spacing_mm": 0.625,
        "integrator.scheme": "imex",
        "integrator.dt_s": "auto",
        "run.duration_s": duration_s + 0.02,
        "output.frame_rate_hz": SIM_RATE_HZ,
        "output.probes_per_frame": 1,
    }
    for key, value in settings.items():
        set_field(data, key, value)
    scene = scene_from_dict(copy.deepcopy(data))
    result = simulate(scene)
    nodes = np.asarray(result.frames, dtype=np.float64)[:, 0] * 1000.0
    clamp = scene.clamp
    description = {
        "scene": "impulsive_rotation",
        "settings": settings,
        "free_length_mm": scene.strip.free_length_mm,
        "clamp_length_mm": scene.strip.clamp_length_mm,
        "n_clamped": scene.n_clamped,
        "n_nodes": scene.n_nodes,
        "clamp_motion": clamp.motion,
        "clamp_segments": [
            {"t_start_s": g.t_start_s, "t_end_s": g.t_end_s, "theta_coefficients_si": list(g.theta_coefficients_si)}
            for g in clamp.segments
        ],
        "rotation_centre_mm": [clamp.rotation_centre_dx_mm, clamp.rotation_centre_dy_mm],
    }
    return Motion(
        times_s=np.asarray(result.frame_times, dtype=np.float64),
        nodes_mm=nodes,
        n_clamped=int(scene.n_clamped),
        spacing_mm=float(scene.strip.spacing_mm),
        free_length_mm=float(scene.strip.free_length_mm),
        description=description,
    )


# ====================================================================== the geometry
def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _normalise(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass
class StripShape:
    """The band about the free midline at one instant: nodes ``p``, node normals ``n``
    (in-plane, towards the +x side face at rest), offset nodes ``a = p + t/2 n`` and
    ``b = p - t/2 n``, and the free end's tangent."""

    p: np.ndarray
    n: np.ndarray
    a: np.ndarray
    b: np.ndarray
    end_tangent: np.ndarray

    @classmethod
    def of(cls, nodes: np.ndarray, n_clamped: int) -> StripShape:
        """The band of the free nodes of ``nodes`` (all nodes, mm)."""
        p = nodes[n_clamped - 2 :]  # one clamped node above, for the first node's normal
        tangent = _normalise(np.diff(p, axis=0))
        seg_n = np.column_stack([-tangent[:, 1], tangent[:, 0]])
        node_n = np.empty((len(p) - 1, 2))
        node_n[:-1] = _normalise(seg_n[:-1] + seg_n[1:])
        node_n[-1] = seg_n[-1]
        free = p[1:]
        h = THICKNESS_MM / 2
        return cls(p=free, n=node_n, a=free + h * node_n, b=free - h * node_n, end_tangent=tangent[-1])

    def edge_point(self, s_mm: np.ndarray, spacing_mm: float) -> np.ndarray:
        """The band's boundary on the -n side (opposite the visible face) at arc lengths ``s_mm``."""
        f = np.asarray(s_mm, dtype=np.float64) / spacing_mm
        i = np.clip(np.floor(f).astype(int), 0, len(self.b) - 2)
        w = (f - i)[:, None]
        return (1.0 - w) * self.b[i] + w * self.b[i + 1]

    def normal_at(self, s_mm: np.ndarray, spacing_mm: float) -> np.ndarray:
        """The interpolated in-plane normal (towards the visible face) at ``s_mm``."""
        f = np.asarray(s_mm, dtype=np.float64) / spacing_mm
        i = np.clip(np.floor(f).astype(int), 0, len(self.n) - 2)
        w = (f - i)[:, None]
        return _normalise((1.0 - w) * self.n[i] + w * self.n[i + 1])


@dataclass
class ClampPose:
    """The clamp's lowest point ``origin`` and its in-plane axes: ``eu`` along the lowest
    line, ``ev`` up the clamp (towards the first clamped node)."""

    origin: np.ndarray
    eu: np.ndarray
    ev: np.ndarray

    @classmethod
    def of(cls, nodes: np.ndarray, n_clamped: int) -> ClampPose:
        """The clamp's pose from the clamped nodes of ``nodes`` (mm)."""
        origin = nodes[n_clamped - 1]
        ev = _normalise(nodes[0] - origin)
        return cls(origin=origin.copy(), eu=np.array([ev[1], -ev[0]]), ev=ev)

    def corners(self) -> np.ndarray:
        """The block's 8 corners in world mm."""
        half = CLAMP_SIZE_MM[0] / 2
        out = []
        for u in (-half, half):
            for v in (0.0, CLAMP_SIZE_MM[1]):
                xy = self.origin + u * self.eu + v * self.ev
                for z in CLAMP_Z_MM:
                    out.append([xy[0], xy[1], z])
        return np.array(out)


# ====================================================================== the backdrop
class Backdrop:
    """The plane z = BACKDROP_Z_MM: a smooth random albedo at three scales (0.3 to 0.6)
    with fine grain, over ``extent`` (x0, x1, y0, y1 mm)."""

    def __init__(self, extent: tuple[float, float, float, float], rng: np.random.Generator) -> None:
        from scipy.ndimage import gaussian_filter

        self.extent = extent
        self.layers: list[tuple[float, np.ndarray, float, int]] = []
        x0, x1, y0, y1 = extent
        for cell, weight, order in ((9.0, 0.55, 3), (3.0, 0.35, 3), (1.0, 0.22, 3), (0.12, 0.0, 1)):
            nx, ny = int((x1 - x0) / cell) + 4, int((y1 - y0) / cell) + 4
            grid = rng.standard_normal((ny, nx))
            grid = gaussian_filter(grid, 1.0 if order == 3 else 0.7, mode="wrap")
            grid /= grid.std()
            self.layers.append((cell, grid, weight, order))

    def albedo(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Grey albedo at backdrop points (mm)."""
        from scipy.ndimage import map_coordinates

        x0, _, y0, _ = self.extent
        smooth = np.zeros_like(x)
        grain = np.zeros_like(x)
        for cell, grid, weight, order in self.layers:
            coords = np.vstack([(y - y0) / cell + 1.0, (x - x0) / cell + 1.0])
            value = map_coordinates(grid, coords, order=order, mode="nearest")
            if weight:
                smooth += weight * value
            else:
                grain = value
        return np.clip(0.45 + 0.1 * np.tanh(smooth / 1.2) * 1.45 + 0.018 * grain, 0.28, 0.62)


def _pool(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The light's smooth spatial falloff (a lamp's pool), 1 at its centre."""
    r2 = (x - POOL_CENTRE_MM[0]) ** 2 + (y - POOL_CENTRE_MM[1]) ** 2
    return 0.55 + 0.45 * np.exp(-r2 / (2 * POOL_SIGMA_MM**2))


def _lambert(normal: np.ndarray) -> np.ndarray:
    return AMBIENT + DIFFUSE * np.clip(normal @ LIGHT_DIR, 0.0, None)


# ====================================================================== the renderer
@dataclass
class Hits:
    """Nearest surface hits of one instant: subsample index, ray length and radiance
    (RGB) of the plain fabric and of the red-edged fabric."""

    sub: np.ndarray
    lam: np.ndarray
    plain: np.ndarray
    dyed: np.ndarray


def _empty_hits() -> Hits:
    return Hits(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))


def _nearest(h: Hits) -> Hits:
    """Keep the nearest hit per subsample."""
    if len(h.sub) == 0:
        return h
    # one sort of a float key: the subsample, plus the ray length scaled into [0, 0.5)
    order = np.argsort(h.sub + np.clip(h.lam, 0.0, 4.9e3) * 1e-4, kind="stable")
    sub = h.sub[order]
    first = np.r_[True, sub[1:] != sub[:-1]]
    keep = order[first]
    return Hits(h.sub[keep], h.lam[keep], h.plain[keep], h.dyed[keep])


def _concat(parts: list[Hits]) -> Hits:
    parts = [p for p in parts if len(p.sub)]
    if not parts:
        return _empty_hits()
    return Hits(
        np.concatenate([p.sub for p in parts]),
        np.concatenate([p.lam for p in parts]),
        np.concatenate([p.plain for p in parts]),
        np.concatenate([p.dyed for p in parts]),
    )


class Rig:
    """The rig: camera, backdrop, per-subsample rays and backdrop radiance, and the
    rendering of instants, frames, boards and the background."""

    def __init__(self, camera: RigCamera, supersample: int = SUPERSAMPLE, seed: int = SEED) -> None:
        self.camera = camera
        self.s = supersample
        self.seed = seed
        self.w, self.h = camera.width, camera.height
        self.ws, self.hs = self.w * self.s, self.h * self.s
        corners = np.array([[0, 0], [self.w - 1, 0], [0, self.h - 1], [self.w - 1, self.h - 1]], dtype=float)
        d = camera.rays(corners)
        lam = (BACKDROP_Z_MM - camera.centre[2]) / d[:, 2]
        hit = camera.centre + lam[:, None] * d
        m = 15.0
        extent = (hit[:, 0].min() - m, hit[:, 0].max() + m, hit[:, 1].min() - m, hit[:, 1].max() + m)
        self.backdrop = Backdrop(extent, np.random.default_rng([seed, 1]))
        self.dirs = np.empty((self.hs * self.ws, 3))
        self.bg_sub = np.empty(self.hs * self.ws)
        for v0 in range(0, self.hs, 240):
            rows = np.arange(v0, min(v0 + 240, self.hs))
            idx = (rows[:, None] * self.ws + np.arange(self.ws)[None, :]).ravel()
            d = camera.rays(self.sub_pixels(idx))
            self.dirs[idx] = d
            self.bg_sub[idx] = self._backdrop_grey(d)
        self.bg_pixel = self.bg_sub.reshape(self.h, self.s, self.w, self.s).mean(axis=(1, 3))

    # -------------------------------------------------------------- subsample bookkeeping
    def sub_pixels(self, idx: np.ndarray, s: int | None = None, ws: int | None = None) -> np.ndarray:
        """Pixel coordinates of subsample indices (row-major over the subsample grid)."""
        s = s or self.s
        ws = ws or self.ws
        v, u = np.divmod(idx, ws)
        return np.column_stack([(u + 0.5) / s - 0.5, (v + 0.5) / s - 0.5])

    def _sub_box(self, px: np.ndarray, pad: float = 1.5) -> tuple[int, int, int, int]:
        lo = (px.min(axis=0) - pad + 0.5) * self.s - 0.5
        hi = (px.max(axis=0) + pad + 0.5) * self.s - 0.5
        u0, v0 = max(int(np.floor(lo[0])), 0), max(int(np.floor(lo[1])), 0)
        u1, v1 = min(int(np.ceil(hi[0])) + 1, self.ws), min(int(np.ceil(hi[1])) + 1, self.hs)
        return u0, u1, v0, v1

    def _box_subs(self, box: tuple[int, int, int, int]) -> np.ndarray:
        u0, u1, v0, v1 = box
        if u1 <= u0 or v1 <= v0:
            return np.zeros(0, int)
        return (np.arange(v0, v1)[:, None] * self.ws + np.arange(u0, u1)[None, :]).ravel()

    def _backdrop_grey(self, d: np.ndarray) -> np.ndarray:
        c = self.camera.centre
        lam = (BACKDROP_Z_MM - c[2]) / d[:, 2]
        x, y = c[0] + lam * d[:, 0], c[1] + lam * d[:, 1]
        normal = np.array([0.0, 0.0, 1.0])
        return self.backdrop.albedo(x, y) * _lambert(normal) * _pool(x, y)

    # -------------------------------------------------------------------- the strip
    def _hull_subs(self, px: np.ndarray, pad: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """The subsamples within ``pad`` px of the convex hull of each item's projected points
        ``px[item, k, 2]``: (item, subsample index) pairs. A subsample row's span of a hull is
        the extent of the crossings of the row with every chord between two of its points."""
        n_items, k = px.shape[:2]
        i, j = np.triu_indices(k, 1)
        ymin, ymax = px[:, :, 1].min(axis=1), px[:, :, 1].max(axis=1)
        v0 = np.clip(np.floor((ymin - pad + 0.5) * self.s - 0.5).astype(int), 0, self.hs)
        v1 = np.clip(np.ceil((ymax + pad + 0.5) * self.s - 0.5).astype(int) + 1, 0, self.hs)
        rows = np.maximum(v1 - v0, 0)
        item = np.repeat(np.arange(n_items), rows)
        row = v0[item] + np.arange(rows.sum()) - np.repeat(np.cumsum(rows) - rows, rows)
        y = (row + 0.5) / self.s - 0.5
        pa, pb = px[item][:, i], px[item][:, j]  # [rows, chords, 2]
        lo = np.full(len(row), np.inf)
        hi = np.full(len(row), -np.inf)
        for dy in (-pad, 0.0, pad):
            yy = np.clip(y + dy, ymin[item], ymax[item])[:, None]
            den = pb[..., 1] - pa[..., 1]
            with np.errstate(divide="ignore", invalid="ignore"):
                w = (yy - pa[..., 1]) / den
            u = pa[..., 0] + w * (pb[..., 0] - pa[..., 0])
            ok = (den != 0) & (w >= 0) & (w <= 1)  # each vertex ends a sloping chord: flat ones can go
            lo = np.minimum(lo, np.where(ok, u, np.inf).min(axis=1))
            hi = np.maximum(hi, np.where(ok, u, -np.inf).max(axis=1))
        u0 = np.clip(np.floor((lo - pad + 0.5) * self.s - 0.5).astype(int), 0, self.ws)
        u1 = np.clip(np.ceil((hi + pad + 0.5) * self.s - 0.5).astype(int) + 1, 0, self.ws)
        count = np.maximum(u1 - u0, 0)
        total = int(count.sum())
        r = np.repeat(np.arange(len(row)), count)
        u = u0[r] + np.arange(total) - np.repeat(np.cumsum(count) - count, count)
        return item[r], row[r] * self.ws + u

    def _strip_hits(self, shape: StripShape) -> Hits:
        c = self.camera.centre
        a, b = shape.a, shape.b
        m = len(a) - 1
        # each segment's prism: 4 offset nodes at z = 0 and z = -W, projected
        quad = np.stack([a[:-1], a[1:], b[1:], b[:-1]], axis=1)  # [m, 4, 2]
        pts = np.concatenate(
            [np.dstack([quad, np.zeros((m, 4, 1))]), np.dstack([quad, np.full((m, 4, 1), -WIDTH_MM)])], axis=1
        )
        px = self.camera.project(pts.reshape(-1, 3)).reshape(m, 8, 2)
        seg, sub = self._hull_subs(px)
        total = len(sub)
        if total == 0:
            return _empty_hits()
        d = self.dirs[sub]
        a0 = -c[2] / d[:, 2]
        a1 = (-WIDTH_MM - c[2]) / d[:, 2]
        p0 = c[:2] + a0[:, None] * d[:, :2]
        delta = (a1 - a0)[:, None] * d[:, :2]
        q = quad[seg]  # [n, 4, 2]
        # near-edge cap (z = 0): P0 inside the segment's quad
        edges = np.roll(q, -1, axis=1) - q
        side = _cross(edges, p0[:, None, :] - q)
        inside = np.all(side >= 0, axis=1) | np.all(side <= 0, axis=1)
        mu = np.where(inside, 0.0, np.inf)
        kind = np.zeros(total, dtype=np.int8)  # 0 cap, 1 wall a, 2 wall b, 3 end
        nu = np.zeros(total)

        def wall(
            v0_: np.ndarray, v1_: np.ndarray, code: int, mu: np.ndarray, mask: np.ndarray | None = None
        ) -> np.ndarray:
            e = v1_ - v0_
            r = v0_ - p0
            den = _cross(delta, e)
            with np.errstate(divide="ignore", invalid="ignore"):
                mu_w = _cross(r, e) / den
                nu_w = _cross(r, delta) / den
            ok = (den != 0) & (mu_w >= 0) & (mu_w <= 1) & (nu_w >= 0) & (nu_w <= 1) & (mu_w < mu)
            if mask is not None:
                ok &= mask
            kind[ok] = code
            nu[ok] = nu_w[ok]
            return np.where(ok, mu_w, mu)

        mu = wall(q[:, 0], q[:, 1], 1, mu)
        mu = wall(q[:, 3], q[:, 2], 2, mu)
        mu = wall(b[-1], a[-1], 3, mu, seg == m - 1)
        hit = np.isfinite(mu)
        seg, sub, d, mu, nu, a0, a1 = (x[hit] for x in (seg, sub, d, mu, nu, a0, a1))
        kind = kind[hit]
        lam = a0 + mu * (a1 - a0)
        point = c + lam[:, None] * d
        normal = np.zeros((len(lam), 3))
        normal[:, 2] = 1.0
        n_seg = (1.0 - nu)[:, None] * shape.n[seg] + nu[:, None] * shape.n[seg + 1]
        n_seg = _normalise(n_seg)
        wa, wb, we = kind == 1, kind == 2, kind == 3
        normal[wa] = np.column_stack([n_seg[wa], np.zeros(wa.sum())])
        normal[wb] = np.column_stack([-n_seg[wb], np.zeros(wb.sum())])
        normal[we] = [shape.end_tangent[0], shape.end_tangent[1], 0.0]
        shade = (_lambert(normal) * _pool(point[:, 0], point[:, 1]))[:, None]
        plain = shade * FABRIC_ALBEDO
        dyed_here = point[:, 2] >= -DYE_DEPTH_MM
        dyed = np.where(dyed_here[:, None], shade * DYE_ALBEDO, plain)
        return _nearest(Hits(sub, lam, plain, dyed))

    # -------------------------------------------------------------------- the clamp
    def _clamp_hits(self, pose: ClampPose) -> Hits:
        c = self.camera.centre
        px = self.camera.project(pose.corners())
        sub = self._box_subs(self._sub_box(px))
        if len(sub) == 0:
            return _empty_hits()
        d = self.dirs[sub]
        rel = c[:2] - pose.origin
        o = np.array([rel @ pose.eu, rel @ pose.ev, c[2]])
        dl = np.column_stack([d[:, :2] @ pose.eu, d[:, :2] @ pose.ev, d[:, 2]])
        lo = np.array([-CLAMP_SIZE_MM[0] / 2, 0.0, CLAMP_Z_MM[0]])
        hi = np.array([CLAMP_SIZE_MM[0] / 2, CLAMP_SIZE_MM[1], CLAMP_Z_MM[1]])
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (lo - o) / dl
            t2 = (hi - o) / dl
        tmin, tmax = np.minimum(t1, t2), np.maximum(t1, t2)
        axis = np.argmax(tmin, axis=1)
        t_near = tmin[np.arange(len(sub)), axis]
        t_far = tmax.min(axis=1)
        hit = (t_near <= t_far) & (t_near > 0)
        sub, d, dl, axis, lam = sub[hit], d[hit], dl[hit], axis[hit], t_near[hit]
        local = o + lam[:, None] * dl
        sign = -np.sign(dl[np.arange(len(lam)), axis])
        n_local = np.zeros((len(lam), 3))
        n_local[np.arange(len(lam)), axis] = sign
        albedo = np.tile(CLAMP_ALBEDO, (len(lam), 1))
        spec_k = np.full(len(lam), 0.04)
        spec_pow = np.full(len(lam), 20.0)
        front = (axis == 2) & (sign > 0)
        for (su, sv), slot in zip(SCREW_CENTRES_MM, SCREW_SLOT_ANGLES, strict=True):
            du, dv = local[:, 0] - su, local[:, 1] - sv
            on = front & (du * du + dv * dv <= SCREW_RADIUS_MM**2)
            if not on.any():
                continue
            hu, hv = du[on] / SCREW_DOME_RADIUS_MM, dv[on] / SCREW_DOME_RADIUS_MM
            n_local[on] = np.column_stack([hu, hv, np.sqrt(np.clip(1 - hu * hu - hv * hv, 0, None))])
            in_slot = np.abs(-np.sin(slot) * du[on] + np.cos(slot) * dv[on]) < 0.3
            alb = np.where(in_slot, 0.10, SCREW_ALBEDO)
            albedo[on] = alb[:, None]
            spec_k[on] = np.where(in_slot, 0.0, 1.2)
            spec_pow[on] = 60.0
        normal = np.column_stack(
            [
                n_local[:, 0] * pose.eu[0] + n_local[:, 1] * pose.ev[0],
                n_local[:, 0] * pose.eu[1] + n_local[:, 1] * pose.ev[1],
                n_local[:, 2],
            ]
        )
        point = c + lam[:, None] * d
        half = _normalise(LIGHT_DIR - d)
        spec = spec_k * np.clip(np.sum(normal * half, axis=1), 0, None) ** spec_pow
        pool = _pool(point[:, 0], point[:, 1])
        rad = albedo * (_lambert(normal) * pool)[:, None] + (spec * pool)[:, None]
        return Hits(sub, lam, rad, rad)

    # ------------------------------------------------------------------- the markers
    def _marker_hits(self, centres: np.ndarray) -> Hits:
        c = self.camera.centre
        r = MARKER_DIAMETER_MM / 2
        ring = np.linspace(0, 2 * np.pi, 12, endpoint=False)
        parts = []
        for centre in centres:
            rim = np.column_stack(
                [centre[0] + r * np.cos(ring), centre[1] + r * np.sin(ring), np.full(12, MARKER_Z_MM)]
            )
            sub = self._box_subs(self._sub_box(self.camera.project(rim)))
            d = self.dirs[sub]
            lam = (MARKER_Z_MM - c[2]) / d[:, 2]
            x, y = c[0] + lam * d[:, 0] - centre[0], c[1] + lam * d[:, 1] - centre[1]
            on = x * x + y * y <= r * r
            sub, lam, x, y = sub[on], lam[on], x[on] + centre[0], y[on] + centre[1]
            shade = MARKER_ALBEDO * _lambert(np.array([0.0, 0.0, 1.0])) * _pool(x, y)
            rad = np.repeat(shade[:, None], 3, axis=1)
            parts.append(Hits(sub, lam, rad, rad))
        return _concat(parts)

    # ------------------------------------------------------------------ one instant
    def instant(self, motion: Motion, t: float, strip: bool = True) -> tuple[Hits, Hits]:
        """The nearest hits at time ``t``: (the markers variant, the red-edge variant)."""
        nodes = motion.nodes_at(t)
        parts = [self._clamp_hits(ClampPose.of(nodes, motion.n_clamped))]
        if strip:
            parts.append(self._strip_hits(StripShape.of(nodes, motion.n_clamped)))
        solid = _nearest(_concat(parts))
        if not strip:
            return solid, solid
        markers = self._marker_hits(motion.midline(nodes, MARKER_S_MM))
        return _nearest(_concat([solid, markers])), solid

    def _accumulate(self, acc: np.ndarray, hits: Hits, dyed: bool) -> None:
        v, u = np.divmod(hits.sub, self.ws)
        pix = (v // self.s) * self.w + u // self.s
        rad = hits.dyed if dyed else hits.plain
        diff = rad - self.bg_sub[hits.sub, None] * BACKDROP_TINT
        for ch in range(3):
            acc[:, ch] += np.bincount(pix, weights=diff[:, ch], minlength=self.w * self.h)

    def exposure_instants(self, motion: Motion, t: float) -> tuple[np.ndarray, float]:
        """The instants of the exposure centred on ``t`` and the longest image path (px)
        of any strip node (near and far edge), marker or clamp corner during it."""
        fine = np.linspace(t - EXPOSURE_S / 2, t + EXPOSURE_S / 2, int(round(EXPOSURE_S * SIM_RATE_HZ)) * 2 + 1)
        track_list = []
        for tt in fine:
            nodes = motion.nodes_at(tt)
            free = motion.free(nodes)
            pts = np.concatenate(
                [
                    np.column_stack([free, np.zeros(len(free))]),
                    np.column_stack([free, np.full(len(free), -WIDTH_MM)]),
                    ClampPose.of(nodes, motion.n_clamped).corners(),
                ]
            )
            track_list.append(self.camera.project(pts))
        tracks = np.array(track_list)
        path = np.linalg.norm(np.diff(tracks, axis=0), axis=2).sum(axis=0).max()
        n = max(MIN_INSTANTS, int(np.ceil(path / MAX_STEP_PX)))
        times = t - EXPOSURE_S / 2 + (np.arange(n) + 0.5) * EXPOSURE_S / n
        return times, float(path)

    def render_frame(self, motion: Motion, t: float) -> tuple[np.ndarray, np.ndarray, int, float]:
        """Mean radiance images ``[h, w, 3]`` over the exposure centred on ``t``: the markers
        variant and the red-edge variant, with the number of instants and the path (px)."""
        times, path = self.exposure_instants(motion, t)
        acc_m = np.zeros((self.w * self.h, 3))
        acc_e = np.zeros((self.w * self.h, 3))
        for tt in times:
            with_markers, solid = self.instant(motion, float(tt))
            self._accumulate(acc_m, with_markers, dyed=False)
            self._accumulate(acc_e, solid, dyed=True)
        scale = 1.0 / (self.s * self.s * len(times))
        bg = self.bg_pixel[..., None] * BACKDROP_TINT
        return (
            bg + (acc_m * scale).reshape(self.h, self.w, 3),
            bg + (acc_e * scale).reshape(self.h, self.w, 3),
            len(times),
            path,
        )

    def render_background(self, motion: Motion) -> np.ndarray:
        """Mean radiance ``[h, w, 3]`` of the rig without the strip, the clamp at rest."""
        hits, _ = self.instant(motion, -1.0, strip=False)
        acc = np.zeros((self.w * self.h, 3))
        self._accumulate(acc, hits, dyed=False)
        return self.bg_pixel[..., None] * BACKDROP_TINT + (acc / self.s**2).reshape(self.h, self.w, 3)

    # ------------------------------------------------------------------- the boards
    def render_board(self, origin: np.ndarray, ex: np.ndarray, ey: np.ndarray) -> np.ndarray:
        """Mean radiance ``[h, w, 3]`` of the chessboard whose inner corner (0, 0) is at
        ``origin`` with unit axes ``ex`` (along a row) and ``ey`` (down a column), in front
        of the backdrop (no strip, no clamp), ``BOARD_SUPERSAMPLE``^2 rays per pixel."""
        s = BOARD_SUPERSAMPLE
        ws = self.w * s
        c = self.camera.centre
        normal = np.cross(ex, ey)
        if normal @ (c - origin) < 0:
            normal = -normal
        nx, ny = BOARD_INNER
        lo_x, hi_x = -BOARD_SQUARE_MM - BOARD_MARGIN_MM, (nx + 1) * BOARD_SQUARE_MM + BOARD_MARGIN_MM
        lo_y, hi_y = -BOARD_SQUARE_MM - BOARD_MARGIN_MM, (ny + 1) * BOARD_SQUARE_MM + BOARD_MARGIN_MM
        out = np.empty(self.h * self.w * 3).reshape(self.h, self.w, 3)
        rows_per = 48
        for r0 in range(0, self.h, rows_per):
            r1 = min(r0 + rows_per, self.h)
            vs = np.arange(r0 * s, r1 * s)
            idx = (vs[:, None] * ws + np.arange(ws)[None, :]).ravel()
            d = self.camera.rays(self.sub_pixels(idx, s, ws))
            grey = self._backdrop_grey(d)
            rgb = grey[:, None] * BACKDROP_TINT
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = ((origin - c) @ normal) / (d @ normal)
            point = c + lam[:, None] * d
            bx, by = (point - origin) @ ex, (point - origin) @ ey
            on = (lam > 0) & (bx >= lo_x) & (bx <= hi_x) & (by >= lo_y) & (by <= hi_y)
            col = np.floor(bx[on] / BOARD_SQUARE_MM).astype(int) + 1
            row = np.floor(by[on] / BOARD_SQUARE_MM).astype(int) + 1
            in_squares = (col >= 0) & (col <= nx) & (row >= 0) & (row <= ny)
            black = in_squares & ((col + row) % 2 == 0)
            albedo = np.where(black, BOARD_ALBEDO[0], BOARD_ALBEDO[1])
            shade = albedo * _lambert(normal) * _pool(point[on, 0], point[on, 1])
            rgb[on] = shade[:, None]
            out[r0:r1] = rgb.reshape(r1 - r0, s, self.w, s, 3).mean(axis=(1, 3))
        return out


# ======================================================================== the sensor
def _vignette(w: int, h: int, lens: KannalaBrandtLens) -> np.ndarray:
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    r2 = ((u - lens.cx) ** 2 + (v - lens.cy) ** 2) / ((w / 2) ** 2 + (h / 2) ** 2)
    return 1.0 - VIGNETTE[0] * r2 - VIGNETTE[1] * r2 * r2


def expose(radiance: np.ndarray, lens: KannalaBrandtLens, rng: np.random.Generator) -> np.ndarray:
    """Radiance ``[h, w, 3]`` → an 8-bit RGB image: optical blur, vignetting, gain,
    shot-like noise (sigma^2 = read^2 + k·DN), rounding and clipping."""
    import cv2

    h, w = radiance.shape[:2]
    blurred = cv2.GaussianBlur(radiance, (0, 0), OPTICAL_BLUR_PX, borderType=cv2.BORDER_REFLECT)
    dn = blurred * _vignette(w, h, lens)[..., None] * GAIN_DN
    sigma = np.sqrt(READ_NOISE_DN**2 + SHOT_NOISE_DN2_PER_DN * np.clip(dn, 0, None))
    noisy = dn + sigma * rng.standard_normal(dn.shape)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


# ========================================================================= the files
def _write_mp4(path: Path, frames: list[np.ndarray]) -> None:
    import av

    def write(tmp: Path) -> None:
        with av.open(str(tmp), "w", format="mp4") as container:
            stream = container.add_stream("libx264", rate=FPS)
            stream.width, stream.height = frames[0].shape[1], frames[0].shape[0]
            stream.pix_fmt = "yuv420p"
            stream.time_base = Fraction(1, FPS)
            stream.codec_context.time_base = Fraction(1, FPS)
            stream.options = {"crf": "18", "preset": "slow"}
            for k, image in enumerate(frames):
                frame = av.VideoFrame.from_ndarray(image, format="rgb24")
                frame.pts, frame.time_base = k, Fraction(1, FPS)
                for packet in stream.encode(frame):
                    container.mux(packet)
            for packet in stream.encode():
                container.mux(packet)

    write_atomically(path, write)


def write_lossless_edge(path: Path, frames: Sequence[int]) -> np.ndarray:
    """The edge video's frames ``frames`` (indices at :data:`FPS`) rendered again, exposed with
    the same noise, and written losslessly with every pixel's colour (FFV1 RGB in AVI, each
    at its own time): what edge.mp4 holds before H.264 stores its colour at 2 × 2 pixels. Too
    large to bundle (0.6 MB a frame); the tests and benchmarks/track_accuracy.py make it.
    Returns the midline these frames show, ``[frame, s, x, y]`` (mm) at the rig's arcs, from
    the motion simulated again, to hold against edge_truth.csv (a change in the simulation
    since would show there)."""
    from warpcloth.track.video import write_video

    motion = simulate_motion(DURATION_S)
    camera = rig_camera()
    rig = Rig(camera)

    def rendered():
        for k in frames:
            radiance = rig.render_frame(motion, k / FPS)[1]
            yield expose(radiance, camera.lens, np.random.default_rng([SEED, 3, k]))

    write_atomically(path, lambda tmp: write_video(tmp, rendered(), list(frames), Fraction(1, FPS)))
    midline = [motion.midline(motion.nodes_at(k / FPS), MARKER_S_MM) for k in frames]
    return np.array(
        [
            [k, s, *point]
            for k, points in zip(frames, midline, strict=True)
            for s, point in zip(MARKER_S_MM, points, strict=True)
        ]
    )


def _write_image(path: Path, image: np.ndarray, params: list[int] | None = None) -> None:
    import cv2

    def write(tmp: Path) -> None:
        bgr = image[..., ::-1] if image.ndim == 3 else image
        if not cv2.imwrite(str(tmp), np.ascontiguousarray(bgr), params or []):
            raise OSError(f"OpenCV could not write {tmp}")

    write_atomically(path, write)


def board_poses() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """The six boards: (name, inner corner (0, 0), row axis, column axis). board_0 lies in
    the strip's plane with rows level and inner corner (1, 1) at the world origin."""
    ex0, ey0 = np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0])
    poses = [("board_0", np.array([-BOARD_SQUARE_MM, BOARD_SQUARE_MM, 0.0]), ex0, ey0)]
    nx, ny = BOARD_INNER
    mid = np.array([(nx - 1) / 2, (ny - 1) / 2]) * BOARD_SQUARE_MM
    centre_world = np.array([26.0, -38.0, 0.0])
    tilts = [(25.0, 0.0, 5.0), (28.0, 90.0, -6.0), (22.0, 200.0, 12.0), (30.0, 300.0, -3.0), (24.0, 140.0, 8.0)]
    shifts = [(4.0, 2.0, 10.0), (-6.0, -3.0, -8.0), (3.0, -2.0, 5.0), (-2.0, 4.0, 0.0), (5.0, 0.0, -12.0)]
    for k, ((tilt, azimuth, spin), shift) in enumerate(zip(tilts, shifts, strict=True), start=1):
        az, ti, sp = np.radians([azimuth, tilt, spin])
        axis = np.array([np.cos(az), np.sin(az), 0.0])
        rot = _rotation(axis, ti) @ _rotation(np.array([0.0, 0.0, 1.0]), sp)
        ex, ey = rot @ ex0, rot @ ey0
        origin = centre_world + np.array(shift) - mid[0] * ex - mid[1] * ey
        poses.append((f"board_{k}", origin, ex, ey))
    return poses


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def board_corners(origin: np.ndarray, ex: np.ndarray, ey: np.ndarray) -> np.ndarray:
    """The board's inner corners in world mm, row by row from the top left ``[rows·cols, 3]``."""
    nx, ny = BOARD_INNER
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    return origin + BOARD_SQUARE_MM * (i.ravel()[:, None] * ex + j.ravel()[:, None] * ey)


def default_out_dir() -> Path:
    """scenes/data/rig/ in the checkout."""
    return Path(str(importlib.resources.files("warpcloth.scenes"))) / "data" / "rig"


def _marker_speed(rig: Rig, motion: Motion, t_end: float) -> tuple[float, float]:
    """The fastest image speed (px/s) of any marker's centre in [0, t_end] and when."""
    keep = motion.times_s <= t_end + 1e-9
    pts = np.array([motion.midline(n, MARKER_S_MM) for n in motion.nodes_mm[keep]])
    k, m = pts.shape[:2]
    px = rig.camera.project(np.column_stack([pts.reshape(-1, 2), np.full(k * m, MARKER_Z_MM)])).reshape(k, m, 2)
    speed = np.linalg.norm(np.diff(px, axis=0), axis=2) / np.diff(motion.times_s[keep])[:, None]
    i = np.unravel_index(np.argmax(speed), speed.shape)
    return float(speed[i]), float(motion.times_s[i[0]])


def main(argv: Sequence[str] | None = None) -> int:
    """Render the rig's files into OUT_DIR (the first argument, else scenes/data/rig/)."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m warpcloth.track.rig",
        description="Film warpcloth's impulsive rotation through an independent 3D rig and camera.",
    )
    parser.add_argument("out_dir", nargs="?", type=Path, default=None, help="default: scenes/data/rig/")
    args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    out = args.out_dir if args.out_dir is not None else default_out_dir()
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    motion = simulate_motion(DURATION_S)
    desc = motion.description
    print(
        f"simulated: free length {desc['free_length_mm']} mm, clamp length {desc['clamp_length_mm']} mm, "
        f"{desc['n_nodes']} nodes ({desc['n_clamped']} clamped), clamp motion {desc['clamp_motion']} "
        f"about {desc['rotation_centre_mm']} mm: {desc['clamp_segments']}"
    )
    free = motion.nodes_mm[:, motion.n_clamped - 1 :]
    print(
        f"the free strip spans x {free[..., 0].min():.1f}..{free[..., 0].max():.1f} mm, "
        f"y {free[..., 1].min():.1f}..{free[..., 1].max():.1f} mm"
    )
    if MARKER_S_MM.max() + MARKER_DIAMETER_MM / 2 > motion.free_length_mm:
        raise InternalError(
            f"the rig's last marker (s = {MARKER_S_MM.max():g} mm) lies beyond the simulated strip's free end "
            f"({motion.free_length_mm:g} mm): the rig and the scene disagree, a bug in warpcloth"
        )
    camera = rig_camera()
    rig = Rig(camera)
    print(f"rig set up in {time.perf_counter() - started:.1f} s; camera centre {np.round(camera.centre, 2).tolist()}")
    n_frames = int(round(DURATION_S * FPS)) + 1
    frames_m: list[np.ndarray] = []
    frames_e: list[np.ndarray] = []
    truth_lines = ["frame,t_s,s_mm,x_mm,y_mm"]
    edge_lines = ["frame,t_s,s_mm,x_mm,y_mm,edge_x_mm,edge_y_mm"]
    per_frame = []
    render_s = []
    for k in range(n_frames):
        t = k / FPS
        t0 = time.perf_counter()
        rad_m, rad_e, n_inst, path = rig.render_frame(motion, t)
        frames_m.append(expose(rad_m, camera.lens, np.random.default_rng([SEED, 2, k])))
        frames_e.append(expose(rad_e, camera.lens, np.random.default_rng([SEED, 3, k])))
        render_s.append(time.perf_counter() - t0)
        nodes = motion.nodes_at(t)
        mid = motion.midline(nodes, MARKER_S_MM)
        edge = StripShape.of(nodes, motion.n_clamped).edge_point(MARKER_S_MM, motion.spacing_mm)
        for s, p, e in zip(MARKER_S_MM, mid, edge, strict=True):
            truth_lines.append(f"{k},{t:.9f},{s:g},{p[0]:.6f},{p[1]:.6f}")
            edge_lines.append(f"{k},{t:.9f},{s:g},{p[0]:.6f},{p[1]:.6f},{e[0]:.6f},{e[1]:.6f}")
        per_frame.append({"frame": k, "t_s": t, "instants": n_inst, "max_path_px": round(path, 3)})
        print(f"frame {k:2d} t {t:.4f} s: {n_inst:3d} instants (path {path:5.1f} px), {render_s[-1]:.1f} s")
    speed, speed_t = _marker_speed(rig, motion, DURATION_S + EXPOSURE_S / 2)
    print(f"fastest marker: {speed:.0f} px/s at t = {speed_t:.4f} s, {speed * EXPOSURE_S:.1f} px per exposure")

    background = expose(rig.render_background(motion), camera.lens, np.random.default_rng([SEED, 4]))
    boards = {}
    for k, (name, origin, ex, ey) in enumerate(board_poses()):
        px = camera.project(board_corners(origin, ex, ey))
        margin = min(
            px[:, 0].min(), px[:, 1].min(), camera.width - 1 - px[:, 0].max(), camera.height - 1 - px[:, 1].max()
        )
        image = expose(rig.render_board(origin, ex, ey), camera.lens, np.random.default_rng([SEED, 5, k]))
        boards[name] = (image, origin, ex, ey, float(margin))
        print(f"{name}: nearest inner corner {margin:.0f} px from the image's edge")

    import cv2

    _write_mp4(out / "rotation.mp4", frames_m)
    _write_mp4(out / "edge.mp4", frames_e)
    for name, (image, *_rest) in boards.items():
        _write_image(out / f"{name}.jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 92])
    grey = cv2.cvtColor(background, cv2.COLOR_RGB2GRAY)
    _write_image(out / "background.png", grey, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    note = (
        "# warpcloth.track.rig: markers' truth (the midline at s, clamp-edge frame, mm, y up) at each frame's "
        f"mid-exposure; truth {TRUTH}\n"
    )
    write_text_atomically(out / "truth.csv", note + "\n".join(truth_lines) + "\n")
    edge_note = (
        "# warpcloth.track.rig edge.mp4 (red near edge, no markers): the midline at s and the near edge's "
        "silhouette on the side opposite the visible face (midline - t/2 n), mm; truth "
        f"{TRUTH}\n"
    )
    write_text_atomically(out / "edge_truth.csv", edge_note + "\n".join(edge_lines) + "\n")
    lens = camera.lens
    record = {
        "generator": "python -m warpcloth.track.rig (independent of warpcloth.track.camera/render)",
        "world_frame": "mm; x right, y up, z towards the camera; origin the clamp's lowest point at rest; "
        "the strip's plane of motion is z = 0 (the calibration plane)",
        "truth": {
            **TRUTH,
            "simulation": desc,
            "interpolation": "node positions linear in time between the 6000 /s frames; at rest before t = 0",
        },
        "camera": {
            "model": "Kannala-Brandt: theta = angle from the optical axis, d = theta + k1 theta^3 + k2 theta^5, "
            "u = cx + fx d x/sqrt(x^2+y^2), v = cy + fy d y/sqrt(x^2+y^2) for camera-frame direction (x right, "
            "y down, z forward); pixel centres at integers",
            "fx": lens.fx,
            "fy": lens.fy,
            "cx": lens.cx,
            "cy": lens.cy,
            "k1": lens.k1,
            "k2": lens.k2,
            "image_size_px": [camera.width, camera.height],
            "centre_mm": camera.centre.tolist(),
            "rotation_world_to_camera": camera.rotation.tolist(),
            "pose": camera.pose,
            "mm_per_px_at_target": camera.pose["distance_mm"] / lens.fx,
        },
        "strip": {
            "thickness_mm": THICKNESS_MM,
            "width_mm": WIDTH_MM,
            "near_edge_z_mm": 0.0,
            "far_edge_z_mm": -WIDTH_MM,
            "visible_side_face": "the +n side (n = the tangent turned +90 degrees; +x at rest)",
            "fabric_albedo_rgb": FABRIC_ALBEDO.tolist(),
            "edge_variant_dye_albedo_rgb": DYE_ALBEDO.tolist(),
            "dye_depth_mm": DYE_DEPTH_MM,
        },
        "markers": {
            "s_mm": MARKER_S_MM.tolist(),
            "diameter_mm": MARKER_DIAMETER_MM,
            "z_mm": MARKER_Z_MM,
            "albedo": MARKER_ALBEDO,
        },
        "clamp": {
            "size_mm": [*CLAMP_SIZE_MM, CLAMP_Z_MM[1] - CLAMP_Z_MM[0]],
            "z_mm": list(CLAMP_Z_MM),
            "albedo_rgb": CLAMP_ALBEDO.tolist(),
            "screws_uv_mm": [list(c) for c in SCREW_CENTRES_MM],
            "screw_diameter_mm": 2 * SCREW_RADIUS_MM,
        },
        "backdrop": {"z_mm": BACKDROP_Z_MM, "albedo_range": [0.28, 0.62], "tint_rgb": BACKDROP_TINT.tolist()},
        "lighting": {
            "direction_to_light": LIGHT_DIR.tolist(),
            "ambient": AMBIENT,
            "diffuse": DIFFUSE,
            "pool_centre_mm": list(POOL_CENTRE_MM),
            "pool_sigma_mm": POOL_SIGMA_MM,
        },
        "exposure": {
            "frame_rate_hz": FPS,
            "exposure_s": EXPOSURE_S,
            "centred_on_frame_time": True,
            "min_instants": MIN_INSTANTS,
            "max_step_px": MAX_STEP_PX,
            "rays_per_pixel": SUPERSAMPLE**2,
            "board_rays_per_pixel": BOARD_SUPERSAMPLE**2,
            "optical_blur_sigma_px": OPTICAL_BLUR_PX,
            "vignetting_at_corner": VIGNETTE,
            "gain_dn_per_radiance": GAIN_DN,
            "noise": f"sigma^2 = {READ_NOISE_DN}^2 + {SHOT_NOISE_DN2_PER_DN:.5f} DN (1.5 DN at 120 DN)",
            "frames": per_frame,
            "fastest_marker_px_per_s": speed,
            "fastest_marker_t_s": speed_t,
        },
        "board": {
            "inner_corners": list(BOARD_INNER),
            "square_mm": BOARD_SQUARE_MM,
            "margin_mm": BOARD_MARGIN_MM,
            "albedo_black_white": list(BOARD_ALBEDO),
            "poses": {
                name: {"corner_0_0_mm": o.tolist(), "row_axis": ex.tolist(), "column_axis": ey.tolist(), "margin_px": m}
                for name, (_, o, ex, ey, m) in boards.items()
            },
            "board_0": "in the plane z = 0, rows level (board X = x, board Y = -y), inner corner (1, 1) at the origin",
            "scene": "the board in front of the backdrop; strip and clamp removed",
        },
        "files": {
            "rotation.mp4": "markers variant; H.264 (libx264, yuv420p, crf 18), 60 frames/s",
            "edge.mp4": "red near edge, no markers; same encoding",
            "board_0.jpg ... board_5.jpg": "chessboards, JPEG quality 92, RGB",
            "background.png": "the rig without the strip, clamp at rest; grey (BT.601 luma of the RGB image)",
            "truth.csv": "frame,t_s,s_mm,x_mm,y_mm: the markers' midline points at each frame's mid-exposure",
            "edge_truth.csv": "as truth.csv plus edge_x_mm,edge_y_mm: the near edge's silhouette opposite the "
            "visible face",
        },
    }
    write_text_atomically(out / "truth.json", json.dumps(record, indent=1) + "\n")
    sizes = {p.name: p.stat().st_size for p in sorted(out.iterdir()) if p.is_file()}
    print(f"rendering took {np.mean(render_s):.1f} s a frame (both variants)")
    print(f"wrote {out} in {time.perf_counter() - started:.0f} s: " + ", ".join(f"{k} {v}" for k, v in sizes.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
