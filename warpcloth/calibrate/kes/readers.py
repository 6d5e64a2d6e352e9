"""KES-FB1 and KES-FB2 loops: read from the instruments' CSV exports (or built from
arrays), their units inferred, validated as the fits need them (docs/model.md §13.1).

**Tensile (KES-FB1)**, a CSV of strain (or extension) and force per width T in gf/cm, in
the order measured: loading from the first row to the maximum strain, then (optionally)
unloading. The unit of the first column comes from its header when the header says
(``strain_percent``, ``strain_%``, ``strain_fraction``, ``extension_mm``; a plain
``strain`` does not say), else from ``strain_unit`` (``percent``, ``fraction`` or
``mm``), else automatically: a column whose maximum exceeds 1 is in percent, otherwise a
fraction (a fabric is never stretched by 100 %, nor loaded to its 500 gf/cm standard
load below 1 % strain). Extension in mm is divided by the gauge length
(``gauge_length_mm``, KES-FB1 standard 50 mm). Units as docs/model.md §1.

**Shear (KES-FB1, shear mode)**, a CSV of shear angle φ in degrees and shear force per
width Fs in gf/cm: one cycle from rest, the standard 0 → +8° → −8° → 0 under the
standard 10 gf/cm tension (:class:`ShearLoop`; docs/model.md §17.1).

**Bending (KES-FB2)**, a CSV of curvature K in 1/cm and moment per width M in
gf·cm/cm: one cycle from rest, e.g. the standard 0 → +2.5 → −2.5 → 0 1/cm, which may go
on with partial (inner) cycles inside ±K0 (:attr:`BendingLoop.inner_start`): the major
loop does not determine how a law treats inner loops, and such a record does (§13.5).

The files are read by :func:`warpcloth.io.csv.read_csv` (the one reader of instrument
files: delimiter, decimal commas, header, comments). Anything wrong with the data is a
DataFileError naming the file (or the arrays' source) and, where one is to blame, the
line; bad ``strain_unit`` and ``gauge_length_mm`` values are ArgumentErrors.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth import units
from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.io.csv import WHITESPACE, Table, read_csv
from warpcloth.units import check_plausible

PERCENT = units.STRAIN_PERCENT
"""Strain written in % → fraction (KES-FB1 files, EMT)."""

KES_FB1_GAUGE_MM = 50.0
"""Standard KES-FB1 gauge length (sample length between the chucks)."""

MIN_LOADING_POINTS = 6
"""The quartic has 4 coefficients; 2 more points leave a residual to judge it by."""

MIN_BENDING_POINTS = 12
"""At least 3 parameters on 3 legs (0 → +K0, +K0 → −K0, −K0 → 0) of a few points each."""

LOOP_CLOSURE = 0.1
"""A loop closes if it ends within this fraction of its largest ``|K|`` of its start."""

LOOP_REACH = 0.5
"""Each sign of curvature must reach this fraction of the loop's largest ``|K|``."""

STRAIN_UNITS = ("percent", "fraction", "mm")
"""The units a KES-FB1 file's first column may be given in (``strain_unit``)."""

_TENSILE_NAMES = ({"strain", "extension", "elongation", "eps", "epsilon"}, {"force", "load", "tension", "t", "f"})
_BENDING_NAMES = ({"curvature", "k", "kappa"}, {"moment", "bending", "m"})
_SHEAR_NAMES = ({"shear", "angle", "phi", "gamma"}, {"shear", "force", "fs", "f"})


@dataclass(frozen=True)
class TensileLoop:
    """A KES-FB1 tensile loop in measurement order: strain (fraction), force per width (gf/cm)."""

    strain: np.ndarray
    force: np.ndarray
    rows: np.ndarray  # where each point came from: file line (1-based) or sample number
    source: str  # file name, or "tensile data"
    row_label: str = "line"
    strain_unit: str = "fraction"  # how the first column was read, and why

    @property
    def turn(self) -> int:
        """Index of the maximum strain: loading is [0, turn], unloading [turn, end]."""
        return int(np.argmax(self.strain))

    @property
    def loading(self) -> slice:
        """The loading (upper) branch."""
        return slice(0, self.turn + 1)

    @property
    def unloading(self) -> slice:
        """The unloading branch (starts at the turn; a single point when there is none)."""
        return slice(self.turn, len(self.strain))


@dataclass(frozen=True)
class BendingLoop:
    """A KES-FB2 bending loop in measurement order: curvature (1/cm), moment per width (gf·cm/cm)."""

    curvature: np.ndarray
    moment: np.ndarray
    rows: np.ndarray
    source: str
    row_label: str = "line"

    @property
    def k0(self) -> float:
        """The loop's largest ``|K|`` (1/cm), where the model's loop closes."""
        return float(np.max(np.abs(self.curvature)))

    @property
    def inner_start(self) -> int | None:
        """Where the partial (inner) cycles begin: the first reversal of K after the major
        cycle has been to both +K0 and −K0; None for a record of the major cycle alone."""
        k = self.curvature
        both = max(int(np.argmax(k)), int(np.argmin(k)))
        step = np.sign(np.diff(k[both:]))
        moving = np.flatnonzero(step)
        turns = moving[1:][step[moving[1:]] != step[moving[:-1]]]
        return both + int(turns[0]) if len(turns) else None

    def legs(self) -> list[slice]:
        """The major cycle's legs: split at its first maximum and first minimum of K, up
        to where the inner cycles begin (the KES values B and 2HB are the major loop's)."""
        end = len(self.curvature) - 1 if self.inner_start is None else self.inner_start
        cuts = sorted({0, int(np.argmax(self.curvature)), int(np.argmin(self.curvature)), end})
        return [slice(a, b + 1) for a, b in zip(cuts[:-1], cuts[1:], strict=False)]


@dataclass(frozen=True)
class ShearLoop:
    """A KES-FB1 shear loop in measurement order: shear angle (degree), shear force per width (gf/cm)."""

    angle: np.ndarray
    force: np.ndarray
    rows: np.ndarray
    source: str
    row_label: str = "line"

    def as_law_loop(self) -> BendingLoop:
        """The same loop in the laws' own variables (the angle for the curvature, the force
        for the moment): what the law fitters read, and where the legs are cut."""
        return BendingLoop(self.angle, self.force, self.rows, self.source, self.row_label)

    @property
    def phi0(self) -> float:
        """The loop's largest ``|φ|`` (degree)."""
        return float(np.max(np.abs(self.angle)))


# ---------------------------------------------------------------------------------- files


def _tokens(name: str) -> list[str]:
    # The words of a column name: "Strain (%)" → strain, percent; "M (gf·cm/cm)" → m, gf, cm, per, cm.
    text = name.lower().replace("%", " percent ").replace("/", " per ")
    return re.findall(r"[a-z0-9]+", text)


def _read_columns(path: str | Path, what: str, names: tuple[str, str], argument: str | None) -> Table:
    # Two numeric columns (see warpcloth.io.csv); a header, if any, of two names.
    table = read_csv(path, 2, what=what, names=names, argument=argument)
    if table.header is not None and len(table.header) != 2:
        spaces = " (with whitespace separation a name cannot contain spaces)" if table.delimiter == WHITESPACE else ""
        raise DataFileError(
            table.path,
            f"the header {table.header_text!r} has {len(table.header)} column names, expected 2{spaces}",
            table.header_line,
        )
    return table


def _check_name(
    path: str | Path, line: int | None, column: int, name: str, words: set[str], units_ok: list[set[str]], expected: str
) -> set[str]:
    # The column's name must be one of ``words`` and any unit it states one of ``units_ok``;
    # returns the unit tokens (what is left of the name).
    tokens = _tokens(name)
    unit = set(tokens) - words - {"per", "width", "of"}
    if not set(tokens) & words or (unit and unit not in units_ok):
        raise DataFileError(str(path), f"header: column {column} is {name!r}; expected {expected}", line)
    return unit


def read_tensile_csv(
    path: str | Path,
    strain_unit: str | None = None,
    gauge_length_mm: float = KES_FB1_GAUGE_MM,
    *,
    argument: str | None = None,
) -> TensileLoop:
    """Read a KES-FB1 loop: columns strain (%, fraction) or extension (mm), force per width (gf/cm).

    ``path`` may also name a bundled example (``kes_fb1_example``); ``argument`` is the
    caller's name for the path, if it wants one blamed (it is blamed when the file cannot be read).

    The first column's unit: the header's when it says, else ``strain_unit`` (percent,
    fraction, mm), else percent when its maximum exceeds 1 and a fraction otherwise.
    """
    if strain_unit is not None and strain_unit not in STRAIN_UNITS:
        raise ArgumentError("strain_unit", f"must be one of {', '.join(STRAIN_UNITS)}; got {strain_unit!r}")
    if not (math.isfinite(gauge_length_mm) and gauge_length_mm > 0):
        raise ArgumentError("gauge_length_mm", f"must be a positive length in mm, got {gauge_length_mm!r}")
    table = _read_columns(path, "KES-FB1 tensile", ("strain", "force"), argument)
    header, values, rows, line = table.header, table.values, table.lines, table.header_line
    unit = strain_unit
    if header is not None:
        first = _check_name(
            path,
            line,
            1,
            header[0],
            _TENSILE_NAMES[0],
            [{"percent"}, {"pct"}, {"fraction"}, {"frac"}, {"mm"}],
            "strain_percent, strain_fraction, strain or extension_mm",
        )
        _check_name(
            path,
            line,
            2,
            header[1],
            _TENSILE_NAMES[1],
            [{"gf", "cm"}],
            "force per width in gf/cm (e.g. force_gf_per_cm; a KES-FB2 bending file has curvature and moment)",
        )
        said = {"percent": "percent", "pct": "percent", "fraction": "fraction", "frac": "fraction", "mm": "mm"}.get(
            next(iter(first), "")
        )
        if said is None and set(_tokens(header[0])) & {"extension", "elongation"}:
            said = strain_unit
            if said != "mm":
                raise DataFileError(
                    str(path),
                    f"header: column 1 is {header[0]!r}: say its unit (extension_mm) or give strain_unit='mm'",
                    line,
                )
        if said and strain_unit and said != strain_unit:
            raise DataFileError(
                str(path),
                f"header: column 1 {header[0]!r} says {said}, but the strain unit was given as {strain_unit}",
                line,
            )
        unit = said or strain_unit
    how = "from the header" if header is not None and unit != strain_unit else "as given"
    if unit is None:
        unit = "percent" if len(values) and np.max(values[:, 0]) > 1 else "fraction"
        how = "guessed: the column's maximum is " + ("above" if unit == "percent" else "at most") + " 1"
    scale = {"percent": PERCENT, "fraction": 1.0, "mm": 1.0 / gauge_length_mm}[unit]
    loop = tensile_loop(values[:, 0] * scale, values[:, 1], source=str(path), rows=rows)
    other = {
        "fraction": "percent (--strain-unit percent)",
        "percent": "a fraction (--strain-unit fraction)",
        "mm": "another gauge length (--gauge-length-mm)",
    }[unit]
    check_plausible(
        "largest tensile strain",
        float(np.max(np.abs(loop.strain))),
        f"{path}, column 1 read as {unit}",
        f"is the column in {other}?",
    )
    described = f"extension in mm over a {gauge_length_mm:g} mm gauge" if unit == "mm" else f"strain in {unit}"
    return dataclasses.replace(loop, strain_unit=f"{described} ({how})")


def _read_loop(
    path: str | Path, what: str, names: tuple[str, str], columns: tuple[tuple, tuple], argument: str | None
) -> Table:
    # A two-column loop file whose header, if any, names each column as ``columns`` say:
    # (the words a name may be, the unit token sets it may state, what is expected).
    table = _read_columns(path, what, names, argument)
    if table.header is not None:
        for column, (name, (words, units_ok, expected)) in enumerate(zip(table.header, columns, strict=True), 1):
            _check_name(path, table.header_line, column, name, words, units_ok, expected)
    return table


def read_bending_csv(path: str | Path, *, argument: str | None = None) -> BendingLoop:
    """Read a KES-FB2 loop: columns curvature (1/cm) and moment per width (gf·cm/cm).

    ``path`` may also name a bundled example (``kes_fb2_example``); ``argument`` is the
    caller's name for the path, if it wants one blamed.
    """
    columns = (
        (
            _BENDING_NAMES[0],
            [{"cm"}, {"1", "cm"}],
            "curvature in 1/cm (e.g. curvature_per_cm; a KES-FB1 tensile file has strain and force)",
        ),
        (_BENDING_NAMES[1], [{"gf", "cm"}], "moment per width in gf·cm/cm (e.g. moment_gf_cm_per_cm)"),
    )
    table = _read_loop(path, "KES-FB2 bending", ("curvature", "moment"), columns, argument)
    return bending_loop(table.values[:, 0], table.values[:, 1], source=str(path), rows=table.lines)


SHEAR_GEOMETRIES = ("fabric", "chuck")
"""How a KES-FB1 shear file's columns are read: the fabric's shear angle and shear force
per width, or the chuck's displacement over the gauge length (a small angle, in degrees)
and its lateral force per width (:func:`fabric_shear` converts them)."""


def fabric_shear(chuck_angle_deg: np.ndarray, chuck_force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fabric's shear angle (degrees) and shear force per width from the chuck's
    reading: displacement d over the fixed gauge length L recorded as the small angle
    d/L (in degrees) and the lateral force F per width. Simple shear at a fixed gauge turns
    the fabric by φ = arctan(d/L), and by virtual work (the chuck's F dd per area L equals
    Fs dφ) its shear force is Fs = F / cos²φ (docs/model.md §17.1)."""
    phi = np.arctan(np.radians(chuck_angle_deg))
    return np.degrees(phi), chuck_force / np.cos(phi) ** 2


def read_shear_csv(path: str | Path, *, argument: str | None = None, geometry: str = "fabric") -> ShearLoop:
    """Read a KES-FB1 shear loop: columns shear angle (degree) and shear force per width (gf/cm).

    ``path`` may also name a bundled example (``kes_fb1_shear_example``); ``argument`` is
    the caller's name for the path, if it wants one blamed. A header that gives the angle
    in radians is refused rather than read as degrees. ``geometry`` says what the columns
    are (:data:`SHEAR_GEOMETRIES`): ``"chuck"`` converts the chuck's reading to the
    fabric's by :func:`fabric_shear`.
    """
    if geometry not in SHEAR_GEOMETRIES:
        raise ArgumentError("geometry", f"must be one of {', '.join(SHEAR_GEOMETRIES)}, got {geometry!r}")
    columns = (
        (
            _SHEAR_NAMES[0],
            [{"deg"}, {"degree"}, {"degrees"}],
            "the shear angle in degrees (e.g. shear_angle_deg; KES-FB1 shear is recorded in degrees)",
        ),
        (_SHEAR_NAMES[1], [{"gf", "cm"}], "shear force per width in gf/cm (e.g. shear_force_gf_per_cm)"),
    )
    table = _read_loop(path, "KES-FB1 shear", ("angle", "force"), columns, argument)
    angle, force = table.values[:, 0], table.values[:, 1]
    if geometry == "chuck":
        angle, force = fabric_shear(angle, force)
    loop = shear_loop(angle, force, source=str(path), rows=table.lines)
    check_plausible(
        "largest shear force", float(np.max(np.abs(loop.force))), f"{path}, column 2", "is it in gf/cm per width?"
    )
    return loop


# ---------------------------------------------------------------------------------- validation


def _error(source: str, label: str, row: object, message: str) -> DataFileError:
    # A file's line goes into the error's line; an array's sample number into its message.
    if label == "line":
        return DataFileError(source, message, int(row))
    return DataFileError(source, f"{label} {row}: {message}")


def _check_finite(
    values: np.ndarray, rows: np.ndarray, source: str, names: tuple[str, str], label: str = "line"
) -> None:
    bad = np.nonzero(~np.isfinite(values))
    if len(bad[0]):
        i, j = int(bad[0][0]), int(bad[1][0])
        raise _error(source, label, rows[i], f"{names[j]} is {values[i, j]}; every value must be finite")


def _paired(
    x: np.ndarray, y: np.ndarray, rows: np.ndarray | None, source: str, names: tuple[str, str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    # Two equally long finite columns, and where each row came from (file line or sample).
    x = np.asarray(x, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    label = "line" if rows is not None else "sample"
    rows = np.arange(1, len(x) + 1) if rows is None else np.asarray(rows)
    if len(x) != len(y):
        raise DataFileError(source, f"{len(x)} {names[0]}s but {len(y)} {names[1]}s")
    _check_finite(np.column_stack([x, y]), rows, source, names, label)
    return x, y, rows, label


def tensile_loop(
    strain: np.ndarray, force: np.ndarray, source: str = "tensile data", rows: np.ndarray | None = None
) -> TensileLoop:
    """A validated tensile loop from arrays: strain as a fraction, force per width in gf/cm.

    Loading runs from the first point to the maximum strain and must not go back in strain;
    unloading, if any, must not go forward. ``rows`` are the file lines of the points
    (None: the points are samples 1, 2, …).
    """
    strain, force, rows, label = _paired(strain, force, rows, source, ("strain", "force"))
    loop = TensileLoop(strain, force, rows, source, label)
    n_loading = loop.turn + 1 if len(strain) else 0
    if n_loading < MIN_LOADING_POINTS:
        raise DataFileError(
            source,
            f"the loading branch (first row to the maximum strain) has {n_loading} "
            f"point(s); fitting the quartic needs at least {MIN_LOADING_POINTS}",
        )
    if not strain[loop.turn] > 0:
        raise DataFileError(source, f"the strain never exceeds 0 (maximum {strain[loop.turn]:g})")
    for part, sign, what in ((loop.loading, 1, "loading"), (loop.unloading, -1, "unloading")):
        index = np.arange(len(strain))[part]
        step = sign * np.diff(strain[part])
        if np.any(step < 0):
            i = int(index[np.nonzero(step < 0)[0][0]])
            raise _error(
                source,
                label,
                rows[i + 1],
                f"strain {strain[i + 1]:.6g} after {strain[i]:.6g} ({label} "
                f"{rows[i]}): the {what} branch must be monotonic in strain (loading runs to the maximum "
                f"strain, {strain[loop.turn]:.6g} at {label} {rows[loop.turn]})",
            )
    return loop


@dataclass(frozen=True)
class _CycleWords:
    # How a loop's checks name its variable: ``x`` and its ``unit``, and what a fit of it needs.
    x: str
    symbol: str
    unit: str
    needs: str


def _check_cycle(x: np.ndarray, rows: np.ndarray, label: str, source: str, words: _CycleWords) -> float:
    # One cycle from rest to both signs of x and back; returns the largest |x|.
    if len(x) < MIN_BENDING_POINTS:
        raise DataFileError(
            source, f"the loop has {len(x)} point(s); {words.needs} needs at least {MIN_BENDING_POINTS}"
        )
    x0 = float(np.max(np.abs(x)))
    if not x0 > 0:
        raise DataFileError(source, f"the {words.x} is 0 throughout")
    low, high = float(x.min()), float(x.max())
    s, u = words.symbol, words.unit
    if high < LOOP_REACH * x0 or low > -LOOP_REACH * x0:
        raise DataFileError(
            source,
            f"the loop does not reach both signs of {words.x}: {s} runs from {low:.4g} to "
            f"{high:.4g}{u}; a loop goes to +{s}0 and −{s}0 (each side at least {LOOP_REACH:.0%} of "
            f"the largest |{s}|)",
        )
    if abs(x[0]) > LOOP_CLOSURE * x0:
        raise DataFileError(
            source,
            f"the loop starts at {s} = {x[0]:.4g}{u} ({label} {rows[0]}), not from rest: the "
            "model starts fresh at the first row, as the instrument's cycle does from 0; give the "
            "cycle from its start",
        )
    if abs(x[-1] - x[0]) > LOOP_CLOSURE * x0:
        raise DataFileError(
            source,
            f"the loop does not close: it starts at {s} = {x[0]:.4g}{u} ({label} {rows[0]}) "
            f"and ends at {s} = {x[-1]:.4g}{u} ({label} {rows[-1]}); a loop returns to its start "
            f"(within {LOOP_CLOSURE:.0%} of the largest |{s}|, {x0:.4g}{u})",
        )
    return x0


_BENDING_WORDS = _CycleWords("curvature", "K", " 1/cm", "fitting D, D1 and α along 0 → +K0 → −K0 → 0")
_SHEAR_WORDS = _CycleWords("shear angle", "φ", "°", "fitting G and the hysteresis along 0 → +φ0 → −φ0 → 0")

SHEAR_ANGLE_RANGE_DEG = (1.0, 45.0)
"""A shear loop's largest ``|φ|`` must lie in this range (degree): KES-FB1 shears to ±8°; a
loop below 1° is most likely in radians, one beyond 45° not a fabric's shear test."""


def bending_loop(
    curvature: np.ndarray, moment: np.ndarray, source: str = "bending data", rows: np.ndarray | None = None
) -> BendingLoop:
    """A validated bending loop from arrays: curvature in 1/cm, moment per width in gf·cm/cm.

    One cycle from rest: it must reach both signs of curvature (each at least half the
    largest ``|K|``) and end within 10 % of the largest ``|K|`` of where it started. ``rows`` as
    for :func:`tensile_loop`.
    """
    curvature, moment, rows, label = _paired(curvature, moment, rows, source, ("curvature", "moment"))
    _check_cycle(curvature, rows, label, source, _BENDING_WORDS)
    return BendingLoop(curvature, moment, rows, source, label)


def shear_loop(
    angle: np.ndarray, force: np.ndarray, source: str = "shear data", rows: np.ndarray | None = None
) -> ShearLoop:
    """A validated shear loop from arrays: angle in degrees, force per width in gf/cm; one
    cycle from rest to both signs of φ and back, as :func:`bending_loop` requires of a
    bending loop, its largest ``|φ|`` within :data:`SHEAR_ANGLE_RANGE_DEG`."""
    angle, force, rows, label = _paired(angle, force, rows, source, ("shear angle", "shear force"))
    phi0 = _check_cycle(angle, rows, label, source, _SHEAR_WORDS)
    low, high = SHEAR_ANGLE_RANGE_DEG
    if not low <= phi0 <= high:
        raise DataFileError(
            source,
            f"the largest shear angle is {phi0:.4g}°, outside {low:g}–{high:g}°: is the "
            "column in degrees? (KES-FB1 shears to ±8°; an angle in radians reads as a loop below "
            "1°: convert it, or head the column shear_angle_deg with the angle in degrees)",
        )
    return ShearLoop(angle, force, rows, source, label)
