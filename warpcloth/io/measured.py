"""Measured data as a lab writes it: CSV files read into SI arrays, with clear errors.

Three forms (comma-, semicolon- or whitespace-separated; one optional header line;
lines starting with ``#`` are comments):

=================  ==========================  =============================================
form               columns                     units
=================  ==========================  =============================================
laser / tip trace  ``t, x``                    s, mm (displacement at the laser line)
tracked shapes     ``frame, t, s, x, y``       -, s, mm (arc length of the marker from the
                                               clamp's lowest point), mm, mm (from the clamp's
                                               lowest point at rest, y up)
clamp encoder      ``t, theta``                s, rad (deg when the header says ``theta_deg``
                                               or ``deg``, or ``angle_unit="deg"`` is given)
=================  ==========================  =============================================
"""

from __future__ import annotations

import importlib.resources
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth import units
from warpcloth.errors import SceneError

_SPLIT = re.compile(r"[,;\s]+")


def bundled_data(name: str | Path) -> Path:
    """``name`` itself if it is a file, else the bundled example of that name
    (``damped_swing_laser`` or ``damped_swing_laser.csv``, from scenes/data/)."""
    path = Path(name)
    if path.is_file():
        return path
    resource = importlib.resources.files("warpcloth.scenes") / "data" / (path.stem + ".csv")
    return Path(str(resource)) if path.parent == Path(".") and resource.is_file() else path


def read_text(path: Path) -> str:
    """A data file's text: UTF-8 (a spreadsheet's byte-order mark dropped), else Latin-1,
    as instrument software on Windows writes it; the numbers are ASCII either way."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def read_table(path: str | Path, n_columns: int | None, what: str, flag: str) -> tuple[np.ndarray, list[str] | None]:
    """Rows of ``n_columns`` numbers (None: as many as the first data row has) from a
    CSV-like file (or a bundled example by name), and its header (None if absent)."""
    path = bundled_data(path)
    try:
        lines = read_text(path).splitlines()
    except OSError as exc:
        raise SceneError(flag, f"cannot read {path}: {exc.strerror}") from None
    numbered = [(i + 1, _SPLIT.split(line.strip())) for i, line in enumerate(lines)
                if line.strip() and not line.lstrip().startswith("#")]
    header = None
    if numbered:
        try:
            float(numbered[0][1][0])
        except ValueError:
            header = [h.strip().lower() for h in numbered[0][1]]
            numbered = numbered[1:]
    if n_columns is None:
        n_columns = len(numbered[0][1]) if numbered else 1
    rows = []
    for line_no, cells in numbered:
        if len(cells) < n_columns:
            raise SceneError(flag, f"{path} line {line_no}: expected {n_columns} columns ({what}), got {len(cells)}")
        try:
            rows.append([float(c) for c in cells[:n_columns]])
        except ValueError as exc:
            raise SceneError(flag, f"{path} line {line_no}: {exc}") from None
    data = np.array(rows, dtype=float).reshape(-1, n_columns)
    if len(data) < 2:
        raise SceneError(flag, f"{path}: expected at least two rows of '{what}', got {len(data)}")
    bad = np.nonzero(~np.isfinite(data).all(axis=1))[0]
    if len(bad):
        raise SceneError(flag, f"{path}: data row {bad[0] + 1} is not finite: {data[bad[0]].tolist()}")
    return data, header


def _increasing(t: np.ndarray, path: str | Path, flag: str) -> None:
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.argmax(step <= 0))
        raise SceneError(flag, f"{path}: times must increase; data row {i + 2} has t = {t[i + 1]:g} after {t[i]:g}")


@dataclass(frozen=True)
class LaserTrace:
    """Displacement at the laser line (or of the tracked tip) against time, SI."""

    t: np.ndarray  # s
    x: np.ndarray  # m


@dataclass(frozen=True)
class TrackedShapes:
    """Markers tracked on the strip, SI: per row the frame, time, arc length s of the
    marker from the clamp's lowest point, and its position from that point at rest."""

    frame: np.ndarray
    t: np.ndarray  # s
    s: np.ndarray  # m
    x: np.ndarray  # m
    y: np.ndarray  # m


def read_laser_trace(path: str | Path, flag: str = "--measured") -> LaserTrace:
    """Read ``t (s), x (mm)``."""
    return _laser_trace(read_table(path, 2, "t_s, x_mm", flag)[0], path, flag)


def _laser_trace(data: np.ndarray, path: str | Path, flag: str) -> LaserTrace:
    _increasing(data[:, 0], path, flag)
    return LaserTrace(data[:, 0], data[:, 1] * units.LENGTH_MM)


def read_tracked_shapes(path: str | Path, flag: str = "--measured") -> TrackedShapes:
    """Read ``frame, t (s), s (mm), x (mm), y (mm)``, ordered by frame with later
    frames at later times."""
    return _tracked_shapes(read_table(path, 5, "frame, t_s, s_mm, x_mm, y_mm", flag)[0], path, flag)


def _tracked_shapes(data: np.ndarray, path: str | Path, flag: str) -> TrackedShapes:
    frame, t = data[:, 0], data[:, 1]
    if np.any(np.diff(frame) < 0) or np.any(np.diff(t)[np.diff(frame) > 0] <= 0):
        raise SceneError(flag, f"{path}: rows must be ordered by frame, and later frames must have later times")
    if np.any(data[:, 2] < 0):
        raise SceneError(flag, f"{path}: arc length s must be ≥ 0 (from the clamp's lowest point), "
                         f"got {data[:, 2].min():g} mm")
    mm = units.LENGTH_MM
    return TrackedShapes(frame.astype(int), t, data[:, 2] * mm, data[:, 3] * mm, data[:, 4] * mm)


def read_encoder(path: str | Path, angle_unit: str | None = None,
                 flag: str = "ENCODER") -> tuple[np.ndarray, np.ndarray]:
    """Read a clamp encoder series ``t (s), theta``; returns (t, θ in rad). The angle
    unit comes from ``angle_unit`` ("rad" or "deg"), else from the header, else rad."""
    data, header = read_table(path, 2, "t_s, theta", flag)
    _increasing(data[:, 0], path, flag)
    if angle_unit is None:
        angle_unit = "deg" if header and any("deg" in cell for cell in header[1:]) else "rad"
    if angle_unit not in ("rad", "deg"):
        raise SceneError("--angle-unit", f"must be rad or deg, got {angle_unit!r}")
    theta = np.radians(data[:, 1]) if angle_unit == "deg" else data[:, 1]
    return data[:, 0], theta


def read_measurement(path: str | Path, flag: str = "--measured") -> LaserTrace | TrackedShapes:
    """A laser trace (2 columns) or tracked shapes (5 columns), told apart by the column count."""
    data, _ = read_table(path, None, "t_s, x_mm  or  frame, t_s, s_mm, x_mm, y_mm", flag)
    if data.shape[1] == 2:
        return _laser_trace(data, path, flag)
    if data.shape[1] == 5:
        return _tracked_shapes(data, path, flag)
    raise SceneError(flag, f"{path} has {data.shape[1]} columns: a laser trace has 2 (t_s, x_mm), "
                     "tracked shapes 5 (frame, t_s, s_mm, x_mm, y_mm)")
