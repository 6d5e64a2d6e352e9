"""The camera and the strip's plane from images of a chessboard, with OpenCV.

Every image is of one board (inner corners ``nx × ny``, squares of ``square_mm``); the
first is the *plane view*, the board held in the strip's plane. All of them together give
the intrinsics and the lens distortion (``cv2.calibrateCamera``, k1, k2, p1, p2; k3 fixed
at 0), the corners found by ``cv2.findChessboardCorners`` and refined by
``cv2.cornerSubPix``. The plane view's pose gives the plane: a pixel, undistorted to ideal
normalised coordinates, maps to the plane by one homography, composed with the move into
warpcloth's clamp-edge frame (x horizontal, y up, mm from the clamp's lowest point),
placed by either a board corner at the clamp's lowest point (the board's rows level) or
two pixels on the clamp's lower edge (the first its lowest point, the second along the
edge towards +x). The result is :class:`PlaneMapping`, stored as ``plane.json``
(docs/file_formats.md).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError, DataFileError

__all__ = ["FORMAT", "PlaneMapping", "calibrate_plane", "read_image", "read_plane"]

FORMAT = "warpcloth plane 1"
"""The ``format`` of a plane.json this code writes and reads."""

MIN_IMAGES = 3
SQUARE_MM = (0.01, 1e4)
"""A chessboard square that can be filmed beside a strip, mm: a side outside is a slip of
unit or digits (1e300 mm would overflow the plane's numbers), refused by name."""
MIN_EDGE_PX = 10
"""--clamp-edge-px's two pixels at least this far apart: a half-pixel error in either then
turns the x axis by at most atan(0.5 / 10) ≈ 3°."""


def read_image(path: str | Path, argument: str = "path", colour: bool = False) -> np.ndarray:
    """A grey image (uint8), or with ``colour`` an RGB one ``[row, column, 3]``, or an error
    naming ``argument`` (missing) or the file (unreadable)."""
    import cv2

    path = Path(path)
    if not path.is_file():
        raise ArgumentError(argument, f"{path} does not exist" if not path.exists() else f"{path} is not a file")
    from PIL import Image, UnidentifiedImageError

    # decoded whole by Pillow first: a truncated or damaged file is then one error naming
    # it, never a partly read image or a codec's own line on stderr (libpng, libjpeg)
    try:
        with Image.open(path) as whole:
            whole.load()
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise DataFileError(path, f"cannot be read as an image (PNG, JPEG, TIFF, BMP): {exc}") from None
    image = cv2.imread(str(path), cv2.IMREAD_COLOR if colour else cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise DataFileError(path, "cannot be read as an image (PNG, JPEG, TIFF, BMP)")
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB) if colour else image


@dataclass(frozen=True)
class PlaneMapping:
    """Pixels ↔ the strip's plane in the clamp-edge frame (mm, y up)."""

    camera_matrix: np.ndarray
    distortion: np.ndarray  # k1, k2, p1, p2, k3
    normalized_to_plane: np.ndarray  # 3 × 3 homography: ideal normalised coordinates → plane mm
    image_size: tuple[int, int]  # width, height, px

    def to_plane(self, pixels: np.ndarray) -> np.ndarray:
        """Pixels ``[n, 2]`` → plane ``[n, 2]`` mm."""
        import cv2

        pts = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
        ideal = cv2.undistortPoints(
            pts,
            self.camera_matrix,
            self.distortion,
            None,
            np.eye(3),
            np.eye(3),
            (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14),
        ).reshape(-1, 2)
        h = self.normalized_to_plane
        w = ideal @ h[2, :2] + h[2, 2]
        return np.column_stack([ideal @ h[0, :2] + h[0, 2], ideal @ h[1, :2] + h[1, 2]]) / w[:, None]

    def raised(self, height_mm: float) -> PlaneMapping:
        """The same camera's mapping onto the plane ``height_mm`` in front of this one (towards
        the camera), in the same in-plane coordinates: what a marker standing off the
        calibrated plane (a sticker's thickness) is measured on, free of the parallax an
        oblique view gives it (height × the tangent of the view's angle to square)."""
        g = np.linalg.inv(self.normalized_to_plane)  # plane (X, Y, 1) → λ (X r1 + Y r2 + t)
        scale = np.sqrt(np.linalg.norm(g[:, 0]) * np.linalg.norm(g[:, 1]))
        r1, r2, t = g[:, 0] / scale, g[:, 1] / scale, g[:, 2] / scale
        normal = np.cross(r1, r2)
        normal /= np.linalg.norm(normal)
        if normal @ t > 0:  # towards the camera, at the origin
            normal = -normal
        lifted = np.column_stack([r1, r2, t + height_mm * normal])
        return PlaneMapping(self.camera_matrix, self.distortion, np.linalg.inv(lifted), self.image_size)

    def to_pixels(self, plane_mm: np.ndarray) -> np.ndarray:
        """Plane ``[n, 2]`` mm → pixels ``[n, 2]``."""
        import cv2

        ideal = np.column_stack([plane_mm, np.ones(len(plane_mm))]) @ np.linalg.inv(self.normalized_to_plane).T
        rays = ideal / ideal[:, 2:]
        pixels, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), self.camera_matrix, self.distortion)
        return pixels.reshape(-1, 2)

    def mm_per_px(self, pixels: np.ndarray) -> np.ndarray:
        """The local scale at each pixel ``[n, 2]``: ``sqrt(abs(det J))`` of the pixel → mm map."""
        step = 0.5
        pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        du = (self.to_plane(pixels + [step, 0]) - self.to_plane(pixels - [step, 0])) / (2 * step)
        dv = (self.to_plane(pixels + [0, step]) - self.to_plane(pixels - [0, step])) / (2 * step)
        return np.sqrt(np.abs(du[:, 0] * dv[:, 1] - du[:, 1] * dv[:, 0]))

    def as_json(self) -> dict:
        """The mapping's part of plane.json."""
        return {
            "image_size_px": list(self.image_size),
            "camera_matrix": self.camera_matrix.tolist(),
            "distortion_k1_k2_p1_p2_k3": self.distortion.tolist(),
            "normalized_to_plane_mm": self.normalized_to_plane.tolist(),
        }


def _corners(image: np.ndarray, path: Path, inner: tuple[int, int]) -> np.ndarray:
    import cv2

    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(image, inner, flags=flags)
    if not found:
        raise DataFileError(
            path,
            f"no chessboard of {inner[0]} × {inner[1]} inner corners found (--board counts "
            "inner corners, columns × rows); the whole board must be in view and in focus",
        )
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 100, 1e-6)
    return cv2.cornerSubPix(image, corners, (5, 5), (-1, -1), criteria).reshape(-1, 2).astype(np.float64)


def _level(corners: np.ndarray, inner: tuple[int, int], path: Path, by_corner: bool) -> np.ndarray:
    # the plane view's corners ordered as the board lies in the image: along a row left to
    # right, rows downwards (findChessboardCorners may start from any end). Relabelling a
    # flat board's corners by a symmetry of their lattice is a rotation of the board, so
    # the calibration is the same; only --origin-corner's counting is fixed by it, and the
    # plane's y (up, against the board's rows' order) by the labels' handedness.
    grid = corners.reshape(inner[1], inner[0], 2)
    along_row = np.abs(grid[:, -1] - grid[:, 0]).mean(axis=0)
    if along_row[1] > along_row[0]:
        # the rows run up the image: the board as counted is turned 90° from how it lies
        if inner[0] == inner[1]:
            grid = grid.transpose(1, 0, 2)
        elif by_corner:
            angle = np.degrees(np.arctan2(along_row[1], along_row[0]))
            raise ArgumentError(
                "inner",
                f"{inner[0]}x{inner[1]}: in the plane view {path.name} the board's rows of {inner[0]} inner corners "
                f"run up the image ({angle:.0f}° from its horizontal), so with the rows level the plane would be "
                f"turned 90°; the board lies as {inner[1]}x{inner[0]} (columns × rows as the plane view shows it), "
                "or, with a camera on its side, place the plane by --clamp-edge-px",
            )
        else:  # the clamp's edge gives x; only the labels' handedness must be the image's
            row, column = grid[0, -1] - grid[0, 0], grid[-1, 0] - grid[0, 0]
            return (grid[:, ::-1] if row[0] * column[1] - row[1] * column[0] < 0 else grid).reshape(-1, 2)
    if grid[0, -1, 0] < grid[0, 0, 0]:
        grid = grid[:, ::-1]
    if grid[-1, 0, 1] < grid[0, 0, 1]:
        grid = grid[::-1]
    return grid.reshape(-1, 2)


def _pixel_pair(text: str, size: tuple[int, int]) -> np.ndarray:
    # two pixels of the plane view (width, height ``size``), far enough apart to give the x axis
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 4 or not np.all(np.isfinite(values)):
        raise ArgumentError(
            "clamp_edge_px",
            f"expected U1,V1,U2,V2 (pixels: the clamp's lowest point, then a point "
            f"along its lower edge towards +x), got {text!r}",
        )
    ends = np.array(values).reshape(2, 2)
    if np.any(ends < 0) or np.any(ends > np.array(size) - 1):
        raise ArgumentError(
            "clamp_edge_px",
            f"{text}: a pixel outside the {size[0]} × {size[1]} px plane view (u 0 "
            f"to {size[0] - 1}, v 0 to {size[1] - 1})",
        )
    if np.linalg.norm(ends[1] - ends[0]) < MIN_EDGE_PX:
        raise ArgumentError(
            "clamp_edge_px",
            f"{text}: the two pixels are {np.linalg.norm(ends[1] - ends[0]):.3g} px "
            f"apart; at least {MIN_EDGE_PX} px are needed to give the edge's direction",
        )
    return ends


def _all_finite(value: object) -> bool:
    # every number in a (nested) record
    if isinstance(value, dict):
        return all(_all_finite(v) for v in value.values())
    if isinstance(value, list | tuple):
        return all(_all_finite(v) for v in value)
    return not isinstance(value, float) or bool(np.isfinite(value))


def calibrate_plane(
    paths: list[str | Path],
    inner: tuple[int, int],
    square_mm: float,
    *,
    origin_corner: tuple[int, int] | None = None,
    clamp_edge_px: str | None = None,
    max_rms_px: float = 0.3,
) -> tuple[PlaneMapping, dict]:
    """The mapping and the full plane.json record from board images, the first the plane
    view. A calibration whose reprojection RMS exceeds ``max_rms_px`` in any image is a
    DataFileError naming the worst image: the images do not fit one camera."""
    import cv2

    if len(paths) < MIN_IMAGES:
        raise ArgumentError(
            "paths",
            f"{len(paths)} board image(s) given; at least {MIN_IMAGES} are needed (the plane "
            "view first, then views in other poses for the lens distortion)",
        )
    if not SQUARE_MM[0] <= square_mm <= SQUARE_MM[1]:
        raise ArgumentError(
            "square_mm",
            f"{square_mm:g} mm is not the side of a chessboard's square filmed beside a strip "
            f"({SQUARE_MM[0]:g} to {SQUARE_MM[1]:g} mm)",
        )
    if (origin_corner is None) == (clamp_edge_px is None):
        raise ArgumentError(
            "origin_corner",
            "give exactly one of --origin-corner I,J and --clamp-edge-px U1,V1,U2,V2 to place the clamp's lowest point",
        )
    if origin_corner is not None and not (0 <= origin_corner[0] < inner[0] and 0 <= origin_corner[1] < inner[1]):
        raise ArgumentError(
            "origin_corner",
            f"{origin_corner[0]},{origin_corner[1]} is not an inner corner of the "
            f"{inner[0]} × {inner[1]} board (0 to {inner[0] - 1}, 0 to {inner[1] - 1})",
        )
    paths = [Path(p) for p in paths]
    images = [read_image(p, "paths") for p in paths]
    size = images[0].shape[::-1]
    for path, image in zip(paths, images, strict=True):
        if image.shape[::-1] != size:
            raise DataFileError(
                path,
                f"is {image.shape[1]} × {image.shape[0]} px, the plane view {paths[0]} is "
                f"{size[0]} × {size[1]}: every image must come from the same camera setting",
            )
    edge = None if clamp_edge_px is None else _pixel_pair(clamp_edge_px, size)
    corners = [_corners(image, path, inner) for path, image in zip(paths, images, strict=True)]
    corners[0] = _level(corners[0], inner, paths[0], by_corner=origin_corner is not None)
    # the board in squares (OpenCV's float32 points hold any board then); mm only afterwards
    board = np.zeros((inner[0] * inner[1], 3), np.float32)
    board[:, :2] = np.mgrid[0 : inner[0], 0 : inner[1]].T.reshape(-1, 2)
    try:
        rms, matrix, distortion, rvecs, tvecs = cv2.calibrateCamera(
            [board] * len(images),
            [c.astype(np.float32).reshape(-1, 1, 2) for c in corners],
            size,
            None,
            None,
            flags=cv2.CALIB_FIX_K3,
            criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12),
        )
    except cv2.error as exc:
        raise DataFileError(
            paths[0], f"OpenCV cannot calibrate a camera from these board images ({exc.err}): no plane file is written"
        ) from None
    view_rms = []
    for c, rvec, tvec in zip(corners, rvecs, tvecs, strict=True):
        projected, _ = cv2.projectPoints(board, rvec, tvec, matrix, distortion)
        view_rms.append(float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - c) ** 2, axis=1)))))
    worst = int(np.argmax(view_rms))
    if view_rms[worst] > max_rms_px:
        listed = ", ".join(f"{p.name} {r:.3g}" for p, r in zip(paths, view_rms, strict=True))
        raise DataFileError(
            paths[worst],
            f"reprojection error {view_rms[worst]:.3g} px exceeds --max-rms-px "
            f"{max_rms_px:g} (per image, px: {listed}): the images do not fit one camera and lens "
            "(a changed zoom or focus, a resized image, or a board that is not flat)",
        )
    r = cv2.Rodrigues(rvecs[0])[0]
    to_board = np.diag([square_mm, square_mm, 1.0]) @ np.linalg.inv(
        np.column_stack([r[:, 0], r[:, 1], tvecs[0].ravel()])
    )
    distortion = distortion.ravel()[:5].astype(np.float64)
    board_mapping = PlaneMapping(matrix, distortion, to_board, (int(size[0]), int(size[1])))
    if origin_corner is not None:
        origin = np.array(origin_corner, dtype=float) * square_mm
        x_axis = np.array([1.0, 0.0])
        placed = {"origin_corner": list(origin_corner), "rows": "level (board x along a row = +x, y up)"}
    else:
        ends = board_mapping.to_plane(edge)
        origin, x_axis = ends[0], (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
        placed = {"clamp_edge_px": edge.tolist()}
    y_axis = np.array([x_axis[1], -x_axis[0]])  # the board's Y runs down the image: up is −Y
    move = np.array([[*x_axis, -x_axis @ origin], [*y_axis, -y_axis @ origin], [0.0, 0.0, 1.0]])
    mapping = PlaneMapping(matrix, distortion, move @ to_board, board_mapping.image_size)
    expected = board[:, :2].astype(np.float64) * square_mm @ np.vstack([x_axis, y_axis]).T - [
        x_axis @ origin,
        y_axis @ origin,
    ]
    plane_error = mapping.to_plane(corners[0]) - expected
    scale = mapping.mm_per_px(corners[0])
    record = {
        "format": FORMAT,
        **mapping.as_json(),
        "board": {"kind": "chessboard", "inner_corners": list(inner), "square_mm": square_mm},
        "origin": placed,
        "reprojection_rms_px": float(rms),
        "plane_view": {
            "image": str(paths[0]),
            "rms_px": view_rms[0],
            "rms_mm": float(np.sqrt(np.mean(np.sum(plane_error**2, axis=1)))),
            "mm_per_px": [float(scale.min()), float(scale.max())],
        },
        "views": [
            {"image": str(p), "sha256": hashlib.sha256(p.read_bytes()).hexdigest(), "rms_px": v}
            for p, v in zip(paths, view_rms, strict=True)
        ],
    }
    if not _all_finite(record):
        raise DataFileError(
            paths[0],
            "the calibration gives numbers that are not finite (a degenerate plane view or "
            "clamp edge); no plane file is written",
        )
    return mapping, record


def read_plane(path: str | Path, argument: str = "path") -> PlaneMapping:
    """The mapping stored in a plane.json by ``warpcloth track calibrate``."""
    from warpcloth.io.json_file import read_json

    path = Path(path)
    if not path.is_file():
        raise ArgumentError(argument, f"{path} does not exist" if not path.exists() else f"{path} is not a file")
    data = read_json(path)
    if data.get("format") != FORMAT:
        raise DataFileError(
            path,
            f"is not a plane file of warpcloth track calibrate (format {data.get('format')!r}, expected {FORMAT!r})",
        )
    try:
        mapping = PlaneMapping(
            np.array(data["camera_matrix"], dtype=float),
            np.array(data["distortion_k1_k2_p1_p2_k3"], dtype=float),
            np.array(data["normalized_to_plane_mm"], dtype=float),
            tuple(int(v) for v in data["image_size_px"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise DataFileError(path, f"is damaged ({type(exc).__name__}: {exc})") from None
    shapes = (mapping.camera_matrix.shape, mapping.distortion.shape, mapping.normalized_to_plane.shape)
    if (
        shapes != ((3, 3), (5,), (3, 3))
        or len(mapping.image_size) != 2
        or not all(
            np.all(np.isfinite(a)) for a in (mapping.camera_matrix, mapping.distortion, mapping.normalized_to_plane)
        )
    ):
        raise DataFileError(
            path,
            "is damaged (camera_matrix 3 × 3, distortion 5 numbers, normalized_to_plane_mm "
            "3 × 3, all finite, are expected)",
        )
    return mapping
