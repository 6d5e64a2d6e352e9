"""A pinhole camera with Brown–Conrady lens distortion, written out in NumPy.

This is the synthetic camera's own model (:mod:`warpcloth.track.render`): it does not call
OpenCV, so the tracker, which calibrates and undistorts with OpenCV, is checked against an
implementation it does not share. The model is OpenCV's five-parameter one (k1, k2, p1,
p2, k3), pixel centres at integer coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Camera", "PlanePose", "rotation"]


@dataclass(frozen=True)
class Camera:
    """Intrinsics (px), distortion (OpenCV's order k1, k2, p1, p2, k3) and image size."""

    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, float, float, float, float]
    width: int
    height: int

    @property
    def matrix(self) -> np.ndarray:
        """The 3 × 3 camera matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def distort(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ideal normalised image coordinates → distorted normalised coordinates."""
        k1, k2, p1, p2, k3 = self.distortion
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
        return (
            x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y,
        )

    def project(self, points: np.ndarray) -> np.ndarray:
        """Camera-frame points ``[..., 3]`` (mm) → pixels ``[..., 2]``."""
        xd, yd = self.distort(points[..., 0] / points[..., 2], points[..., 1] / points[..., 2])
        return np.stack([self.fx * xd + self.cx, self.fy * yd + self.cy], axis=-1)

    def rays(self, u: np.ndarray, v: np.ndarray, iterations: int = 60) -> tuple[np.ndarray, np.ndarray]:
        """Pixels → ideal normalised coordinates, by Newton's method on :meth:`distort`
        (converged far below 1e-9 px for the distortions used here; the caller checks)."""
        xd, yd = (u - self.cx) / self.fx, (v - self.cy) / self.fy
        x, y = xd.copy(), yd.copy()
        step = 1e-7
        for _ in range(iterations):
            fx, fy = self.distort(x, y)
            rx, ry = fx - xd, fy - yd
            ax, ay = self.distort(x + step, y)
            bx, by = self.distort(x, y + step)
            j11, j21 = (ax - fx) / step, (ay - fy) / step
            j12, j22 = (bx - fx) / step, (by - fy) / step
            det = j11 * j22 - j12 * j21
            x -= (j22 * rx - j12 * ry) / det
            y -= (j11 * ry - j21 * rx) / det
        return x, y


def rotation(about_x_deg: float, about_y_deg: float, about_z_deg: float) -> np.ndarray:
    """R = Rz · Ry · Rx for angles in degrees."""
    a, b, c = np.radians([about_x_deg, about_y_deg, about_z_deg])
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


@dataclass(frozen=True)
class PlanePose:
    """A plane in front of the camera: its point (X, Y, 0) (mm) is R·(X, Y, 0) + t in the
    camera frame."""

    rotation: np.ndarray
    translation: np.ndarray  # mm

    def to_camera(self, xy: np.ndarray) -> np.ndarray:
        """Plane points ``[..., 2]`` (mm) → camera-frame points ``[..., 3]`` (mm)."""
        r = self.rotation
        return xy[..., :1] * r[:, 0] + xy[..., 1:2] * r[:, 1] + self.translation

    def from_rays(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the rays through normalised coordinates (x, y) meet the plane (mm)."""
        homography = np.column_stack([self.rotation[:, 0], self.rotation[:, 1], self.translation])
        inverse = np.linalg.inv(homography)
        w = inverse[2, 0] * x + inverse[2, 1] * y + inverse[2, 2]
        return (
            (inverse[0, 0] * x + inverse[0, 1] * y + inverse[0, 2]) / w,
            (inverse[1, 0] * x + inverse[1, 1] * y + inverse[1, 2]) / w,
        )

    def shifted(self, origin_xy: tuple[float, float]) -> PlanePose:
        """The same plane with its coordinates measured from ``origin_xy``."""
        return PlanePose(self.rotation, self.to_camera(np.array(origin_xy, dtype=float)))
