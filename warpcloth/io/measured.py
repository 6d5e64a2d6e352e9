"""Measured data as a lab writes it: CSV files read into SI arrays, with clear errors.

Three forms, each read by :func:`warpcloth.io.csv.read_csv` (delimiter ``,`` ``;`` tab or
whitespace, decimal commas, one optional header line, ``#`` comments; see there):

=================  ==========================  =============================================
form               columns                     units
=================  ==========================  =============================================
laser / tip trace  ``t, x``                    s, mm (displacement at the laser line)
tracked shapes     ``frame, t, s, x, y``       -, s, mm (arc length of the marker from the
                                               clamp's lowest point), mm, mm (from the clamp's
                                               lowest point at rest, y up); ``warpcloth
                                               track`` adds ``u_px, u_mm`` (u_mm judges a fit)
clamp encoder      ``t, theta``                s, rad (``angle_unit`` overrides the header)
sheet markers      ``t, marker, x, y, z``      s, -, mm (the index of the marker in the sheet
                   (a header names them; any   scene's ``output.markers``; positions from the
                   one to three of x, y, z)    clamp edge's middle at rest, y up, z across)
=================  ==========================  =============================================

**Units in the header are honoured**: a header name may end in a unit, after an
underscore or in brackets (``t_ms``, ``x_m``, ``theta_deg``, ``time [ms]``, ``x (cm)``;
:data:`warpcloth.units.MEASURED_UNITS` lists them); a name without one (``t``, ``x``)
takes the form's unit above; a unit that is not one of the column's quantity (``x_s``,
``t_in``, ``x [furlong]``, ``x_furlong``) is an error naming the file, line and column:
whatever is in brackets at the end of a name is its unit, and so is what follows its last
underscore unless that is a name word (``laser_x``, ``x_tip``: :data:`NAME_WORDS`). Columns beyond those a form has
are ignored. Anything wrong in a file is a
DataFileError naming the file (and the line, where one is to blame); a file that cannot
be read at all is an ArgumentError of the argument that named it (``argument``: the
caller's name for the path, ``path`` by default).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth import units
from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.units import check_plausible

from .csv import Table, bundled_data, read_csv, read_text

__all__ = [
    "ClampAngleTrace",
    "LaserTrace",
    "SheetMarkers",
    "TrackedShapes",
    "bundled_data",
    "read_encoder",
    "read_laser_trace",
    "read_measurement",
    "read_sheet_markers",
    "read_table",
    "read_text",
    "read_tracked_shapes",
]

_LASER = ("t_s", "x_mm")
_SHAPES = ("frame", "t_s", "s_mm", "x_mm", "y_mm")
_ENCODER = ("t_s", "theta")
UNCERTAINTY_COLUMNS = ("u_px", "u_mm")
"""The columns ``warpcloth track`` adds after a tracked shape's five: each coordinate's
standard uncertainty (px, mm). A fit judges its RMS against u_mm (its RMS over the points):
what the tracker says it measured to, not the data's own scatter."""
ALONG_COLUMN = "u_along_mm"
"""The column a curve's tracker (the dyed edge, the centreline) adds after u_mm: each
point's standard uncertainty along the strip (mm). A curve is found where it lies; which
material point is where along it comes from an arc measured from the free end, whose
error every point of a frame shares, so there u_mm is the uncertainty across the strip;
the fit takes each frame's mean out of the along-strip residuals (one unknown per frame)
and compares the rest, the points' own error, as it compares across."""


def read_table(
    path: str | Path, n_columns: int | None, what: str, argument: str, names: tuple[str, ...] | None = None
) -> Table:
    """At least two rows of ``n_columns`` numbers (None: as many as the first data row
    has; more are ignored) from a measured-data file or a bundled example by name."""
    table = read_csv(path, n_columns, what=what, names=names, extra_columns=True, argument=argument)
    if len(table.values) < 2:
        columns = f" ({', '.join(names)})" if names else ""
        raise DataFileError(table.path, f"expected at least two rows of {what}{columns}, got {len(table.values)}")
    return table


_QUANTITY = {
    "t_s": ("time", "s"),
    "x_mm": ("length", "mm"),
    "y_mm": ("length", "mm"),
    "s_mm": ("length", "mm"),
    "theta": ("angle", "rad"),
    "frame": (None, None),
    "marker": (None, None),
    "z_mm": ("length", "mm"),
}
_BRACKETED = re.compile(r"\s*[\[(]\s*([^\[\]()]*?)\s*[\])]\s*$")
_SUFFIX = re.compile(r"_([A-Za-zµ%]+)\s*$")


NAME_WORDS = {
    "t",
    "time",
    "x",
    "y",
    "s",
    "theta",
    "angle",
    "phi",
    "frame",
    "tip",
    "laser",
    "marker",
    "encoder",
    "clamp",
    "pos",
    "position",
    "disp",
    "displacement",
    "arc",
    "raw",
}
"""Words that may end a column's name after an underscore without being a unit
(``laser_x``, ``tip_x``, ``x_tip``); any other ending after an underscore is read as a
unit, and refused unless it is one of the column's quantity."""


def stated_unit(name: str) -> str | None:
    """The unit a header name states: in brackets at its end (``time [ms]``, ``x (cm)``:
    whatever is written there), or after its last underscore (``t_ms``, ``x_furlong``)
    unless that ending is a name (:data:`NAME_WORDS`); None when it states none."""
    bracketed = _BRACKETED.search(name)
    if bracketed is not None:
        return bracketed.group(1)
    suffix = _SUFFIX.search(name)
    if suffix is None or suffix.group(1).lower() in NAME_WORDS:
        return None
    return suffix.group(1)


def header_unit(table: Table, column: int, role: str) -> float:
    """Factor to SI of ``column`` (0-based) for its ``role`` (a name of the form, e.g.
    ``x_mm``), from the unit its header names, else the role's own unit. A stated unit
    that is not one of the role's quantity (``x [furlong]``, ``t_in``) is refused."""
    quantity, default = _QUANTITY[role]
    if quantity is None:
        return 1.0
    known = units.MEASURED_UNITS[quantity]
    if not table.header or column >= len(table.header):
        return known[default]
    name = table.header[column]
    unit = stated_unit(name)
    if unit is None:
        return known[default]
    if unit not in known and unit.lower() not in known:
        raise DataFileError(
            table.path,
            f"column {column + 1} is headed {name!r}: {unit!r} is not "
            f"{'an' if quantity == 'angle' else 'a'} {quantity} unit (known: {', '.join(known)}); "
            f"write e.g. {role.split('_')[0]}_{default}, or a name without a unit for {default}",
            table.header_line,
        )
    return known.get(unit, known.get(unit.lower()))


def _scaled(table: Table, roles: tuple[str, ...]) -> np.ndarray:
    """The table's first ``len(roles)`` columns in SI, each by its header's unit."""
    data = table.values[:, : len(roles)].copy()
    for column, role in enumerate(roles):
        data[:, column] *= header_unit(table, column, role)
    return data


def _plausible(table: Table, column: int, quantity: str, value: float, guess: str) -> None:
    # a column whose header states no unit, read in the form's own: warn when its numbers
    # look like another unit's (metres or milliseconds without a unit in the header)
    if table.header and column < len(table.header) and stated_unit(table.header[column]) is not None:
        return
    said = f"headed {table.header[column]!r}" if table.header and column < len(table.header) else "without a header"
    check_plausible(quantity, value, f"{table.path}, column {column + 1} ({said}, no unit)", guess)


def _increasing(table: Table, t: np.ndarray) -> None:
    _plausible(table, 0, "record length", float(t[-1] - t[0]), "milliseconds? head the column t_ms")
    step = np.diff(t)
    if len(step) and np.all(step > 0):
        _plausible(table, 0, "sampling interval", float(np.median(step)), "milliseconds? head the column t_ms")
    if np.any(step <= 0):
        i = int(np.argmax(step <= 0))
        raise DataFileError(
            table.path,
            f"times must increase; t = {t[i + 1]:g} after {t[i]:g} (line {table.lines[i]})",
            int(table.lines[i + 1]),
        )


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
    u: np.ndarray | None = None  # m: each coordinate's standard uncertainty, as the tracker stated it
    u_along: np.ndarray | None = None  # m: a curve's point's along the strip (then u is across it)


def read_laser_trace(path: str | Path, argument: str = "path") -> LaserTrace:
    """Read ``t (s), x (mm)``."""
    return _laser_trace(read_table(path, 2, "laser trace", argument, _LASER))


def _laser_trace(table: Table) -> LaserTrace:
    data = _scaled(table, _LASER)
    _increasing(table, data[:, 0])
    _plausible(
        table,
        1,
        "largest displacement",
        float(np.max(np.abs(data[:, 1]))) / units.LENGTH_MM,
        "metres? head the column x_m",
    )
    return LaserTrace(data[:, 0], data[:, 1])


def read_tracked_shapes(path: str | Path, argument: str = "path") -> TrackedShapes:
    """Read ``frame, t (s), s (mm), x (mm), y (mm)``, ordered by frame with later
    frames at later times."""
    return _tracked_shapes(read_table(path, 5, "tracked shapes", argument, _SHAPES))


def _tracked_shapes(table: Table) -> TrackedShapes:
    data, lines = _scaled(table, _SHAPES), table.lines
    frame, t = data[:, 0], data[:, 1]
    _plausible(table, 1, "record length", float(t[-1] - t[0]), "milliseconds? head the column t_ms")
    disordered = (np.diff(frame) < 0) | ((np.diff(frame) > 0) & (np.diff(t) <= 0))
    if np.any(disordered):
        i = int(np.argmax(disordered))
        raise DataFileError(
            table.path,
            f"frame {frame[i + 1]:g} at t = {t[i + 1]:g} s after frame {frame[i]:g} at "
            f"t = {t[i]:g} s (line {lines[i]}): rows must be ordered by frame, and later frames "
            "must have later times",
            int(lines[i + 1]),
        )
    if np.any(data[:, 2] < 0):
        i = int(np.argmax(data[:, 2] < 0))
        raise DataFileError(
            table.path,
            f"arc length s must be ≥ 0 (from the clamp's lowest point), got {table.values[i, 2]:g}",
            int(lines[i]),
        )
    u, u_along = None, None
    if table.values.shape[1] >= 7 and table.header is not None and tuple(table.header[5:7]) == UNCERTAINTY_COLUMNS:
        u = _positive_uncertainty(table, 6, "u_mm")
        if table.values.shape[1] >= 8 and table.header[7] == ALONG_COLUMN:
            u_along = _positive_uncertainty(table, 7, ALONG_COLUMN)
    return TrackedShapes(frame.astype(int), t, data[:, 2], data[:, 3], data[:, 4], u, u_along)


def _positive_uncertainty(table: Table, column: int, name: str) -> np.ndarray:
    values = table.values[:, column] * units.LENGTH_MM
    bad = ~(np.isfinite(values) & (values > 0))
    if np.any(bad):
        i = int(np.argmax(bad))
        raise DataFileError(
            table.path, f"{name} must be a positive uncertainty, got {table.values[i, column]:g}", int(table.lines[i])
        )
    return values


@dataclass(frozen=True)
class ClampAngleTrace:
    """A clamp encoder's rotation angle against time, SI."""

    t: np.ndarray  # s
    theta: np.ndarray  # rad


_ANGLE_NAME = re.compile(r"^\s*(theta|angle|phi|encoder|clamp)", re.IGNORECASE)


def is_angle_column(table: Table, column: int) -> bool:
    """Whether ``column``'s header names an angle: ``theta``, ``angle``, ``phi``, ``encoder``
    or ``clamp...`` at its start, or an angle unit at its end (``theta_deg``, ``(rad)``)."""
    if not table.header or column >= len(table.header):
        return False
    name = table.header[column]
    return bool(_ANGLE_NAME.match(name)) or stated_unit(name) in units.MEASURED_UNITS["angle"]


def read_encoder(
    path: str | Path, angle_unit: str | None = None, argument: str = "path"
) -> tuple[np.ndarray, np.ndarray]:
    """Read a clamp encoder series ``t (s), theta``; returns (t, θ in rad). The angle
    unit comes from ``angle_unit`` ("rad" or "deg"), else from the header, else rad."""
    if angle_unit not in (None, "rad", "deg"):
        raise ArgumentError("angle_unit", f"must be rad or deg, got {angle_unit!r}")
    trace = _clamp_angle(read_table(path, 2, "encoder", argument, _ENCODER), angle_unit)
    return trace.t, trace.theta


def _clamp_angle(table: Table, angle_unit: str | None = None) -> ClampAngleTrace:
    data = _scaled(table, _ENCODER)
    _increasing(table, data[:, 0])
    if angle_unit is None:
        _plausible(
            table,
            1,
            "largest clamp angle",
            float(np.max(np.abs(data[:, 1]))),
            "degrees? head the column theta_deg, or give --angle-unit deg",
        )
    else:
        said = (stated_unit(table.header[1]) or "").lower() if table.header and len(table.header) > 1 else ""
        if said in units.MEASURED_UNITS["angle"] and said != angle_unit:
            raise ArgumentError(
                "angle_unit",
                f"{angle_unit} contradicts the header of {table.path}, whose column 2 "
                f"is {table.header[1]!r}; drop --angle-unit or fix the header",
            )
        data[:, 1] = table.values[:, 1] * units.MEASURED_UNITS["angle"][angle_unit]
    return ClampAngleTrace(data[:, 0], data[:, 1])


def read_measurement(
    path: str | Path, argument: str = "path", encoder: bool = False
) -> LaserTrace | TrackedShapes | ClampAngleTrace:
    """A laser trace (2 columns), tracked shapes (5 columns), told apart by the column
    count, or, with ``encoder``, a clamp encoder (2 columns, the second headed as an angle:
    :func:`is_angle_column`). An encoder where none is expected is refused: read as a
    laser trace its angles would pass for millimetres."""
    table = read_table(path, None, "measured motion", argument)
    n = table.values.shape[1]
    if n == 2 and is_angle_column(table, 1):
        if encoder:
            return _clamp_angle(table)
        raise DataFileError(
            table.path,
            f"is a clamp encoder (column 2 is headed {table.header[1]!r}), not a "
            "motion of the strip; fit the clamp's motion with `warpcloth clamp fit-angle`",
            table.header_line,
        )
    if n == 2:
        return _laser_trace(table)
    if n == 5 or (
        n in (7, 8)
        and table.header is not None
        and tuple(table.header[5:7]) == UNCERTAINTY_COLUMNS
        and (n == 7 or table.header[7] == ALONG_COLUMN)
    ):
        return _tracked_shapes(table)
    raise DataFileError(
        table.path,
        f"has {n} columns: a laser trace has 2 (t_s, x_mm), tracked shapes 5 "
        "(frame, t_s, s_mm, x_mm, y_mm), or 7 or 8 as warpcloth track writes them (… u_px, u_mm[, u_along_mm])",
        int(table.lines[0]),
    )


MAX_MARKER_DISTANCE_M = 10.0
"""A tracked sheet marker farther than this from the clamp (m) is a unit mistake, refused."""


@dataclass(frozen=True)
class SheetMarkers:
    """Markers tracked on a sheet, SI: per row the time, the marker (its index in the
    scene's ``output.markers``) and the coordinates the camera saw, ``axes`` (a subset of
    ``"xyz"``, in that order), from the middle of the clamp edge at rest."""

    t: np.ndarray  # s
    marker: np.ndarray  # int
    axes: str
    position: np.ndarray  # [row, axis], m


def read_sheet_markers(path: str | Path, argument: str = "path") -> SheetMarkers:
    """Read a sheet's tracked markers: a header naming ``t``, ``marker`` and one to three of
    ``x``, ``y``, ``z`` (any order; units in the names honoured, else s and mm), rows in
    time order (several markers may share a time)."""
    table = read_table(path, None, "sheet markers", argument)
    if not table.header:
        raise DataFileError(
            table.path, "sheet markers need a header naming their columns: t_s, marker, and x_mm, y_mm, z_mm (1 to 3)"
        )
    roles: dict[str, int] = {}
    for column, name in enumerate(table.header):
        stem = _BRACKETED.sub("", name).strip().lower().split("_")[0]  # t_s, y (cm) → t, y
        role = {"t": "t_s", "time": "t_s", "marker": "marker", "x": "x_mm", "y": "y_mm", "z": "z_mm"}.get(stem)
        if role is None:
            continue
        if role in roles:
            raise DataFileError(
                table.path, f"two columns are {stem!r} (columns {roles[role] + 1} and {column + 1})", table.header_line
            )
        roles[role] = column
    axes = "".join(a for a in "xyz" if f"{a}_mm" in roles)
    if "t_s" not in roles or "marker" not in roles or not axes:
        raise DataFileError(
            table.path,
            f"the header {table.header_text!r} must name t, marker and at least one of x, y, z "
            "(e.g. t_s, marker, z_mm, y_mm for a camera facing the sheet)",
            table.header_line,
        )
    t = table.values[:, roles["t_s"]] * header_unit(table, roles["t_s"], "t_s")
    _plausible(table, roles["t_s"], "record length", float(t[-1] - t[0]), "milliseconds? head the column t_ms")
    if np.any(np.diff(t) < 0):
        i = int(np.argmax(np.diff(t) < 0))
        raise DataFileError(
            table.path, f"times must not decrease; t = {t[i + 1]:g} after {t[i]:g}", int(table.lines[i + 1])
        )
    marker = table.values[:, roles["marker"]]
    bad = (marker < 0) | (marker != np.round(marker))
    if bad.any():
        i = int(np.argmax(bad))
        raise DataFileError(table.path, f"marker must be a whole number ≥ 0, got {marker[i]:g}", int(table.lines[i]))
    position = np.column_stack(
        [table.values[:, roles[f"{a}_mm"]] * header_unit(table, roles[f"{a}_mm"], f"{a}_mm") for a in axes]
    )
    far = np.abs(position).max(axis=1) > MAX_MARKER_DISTANCE_M
    if far.any():
        i = int(np.argmax(far))
        raise DataFileError(
            table.path,
            f"a marker {np.abs(position[i]).max():.3g} m from the middle of the clamp edge is no marker on a "
            f"sheet: are the numbers in the unit the header says (mm unless it names one)?",
            int(table.lines[i]),
        )
    return SheetMarkers(t, marker.astype(int), axes, position)
