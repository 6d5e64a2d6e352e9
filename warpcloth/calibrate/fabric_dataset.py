"""The real-fabric bending dataset of Feng et al. 2022, read in place and converted to SI.

Xudong Feng, Wenchao Huang, Weiwei Xu and Huamin Wang, *Learning-Based Bending Stiffness
Parameter Estimation by a Drape Tester*, ACM Transactions on Graphics 41(6), SIGGRAPH Asia
2022, doi:10.1145/3550454.3555464. Its repository,
https://github.com/DrapeTester/ClothDrapeTester, holds ``dataset/dataset.csv``: "the
618-fabric parameter dataset" (the repository's readme), one row per fabric sample, whose
bending parameters the authors collected with "the traditional cantilever test" (the
paper's abstract). The file is **not bundled** with warpcloth: the repository states no
licence for it (its only licence file, ``bending_validation/LICENSE``, puts that folder's
MATLAB code under CC-BY-NC-ND 4.0), so it cannot be redistributed under warpcloth's MIT
licence. :func:`read_feng2022` reads a copy the user fetched, from a path or from the
environment variable :data:`FENG2022_ENV`.

The file's seven columns are the parameters of the authors' bending model in their ArcSim
(``arcsim/AdaptiveCloth/physics.cpp``, ``principal_curvature_based_bending_force``): the
bending moment per width is M(κ) = k₁ κ + k₂ κ², with k₁ and k₂ given along the warp, the
weft and the diagonal (ArcSim's "bias", 45°) and interpolated between them by the
direction's angle. The header names the units: ``density[kg.m-2]`` (areal density, kg/m²),
``linear ...[SI*1e9]`` (k₁ in SI, N·m = N·m²/m, times 10⁹) and ``nonlinear ...[SI*1e12]``
(k₂ in SI, N·m², times 10¹²; mostly negative, a rigidity that softens as the curvature
grows). Each column is converted to SI in one place, :data:`COLUMNS`.

k₁ is the bending rigidity per width B at small curvature, the quantity a cantilever's
bending length c = (B / (ρ_A g))^{1/3} measures for a linear material
(:func:`bending_length`). The repository does not say how the cantilever readings became
k₁ and k₂ (Peirce's c = ℓ/2 at 41.5° gives one number per direction, the model two), so
the c this module computes is the linear model's, not a reading of the file.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.io.csv import read_text

FENG2022_URL = "https://github.com/DrapeTester/ClothDrapeTester"
"""The repository of Feng et al. 2022, which holds the dataset."""

FENG2022_FILE = "dataset/dataset.csv"
"""The dataset's path inside :data:`FENG2022_URL`."""

FENG2022_COMMIT = "24a980c0c78da5cc4af36c8b6e67326b96a1de8f"
"""The repository's commit the reader was written against (its only one, 14 Sep 2022)."""

FENG2022_SHA256 = "f8ded32ac87d2ccb9121a034b32730a62a66bb03a39bb3a0c2d38d9b3c2f8764"
"""SHA-256 of :data:`FENG2022_FILE` at :data:`FENG2022_COMMIT` (618 rows, 251 distinct)."""

FENG2022_ENV = "WARPCLOTH_FENG2022_CSV"
"""The environment variable :func:`read_feng2022` reads the file's path from when given none."""

STANDARD_GRAVITY = 9.80665
"""g in m/s² (the standard gravity, as the KES units of :mod:`warpcloth.units`)."""

COLUMNS = (
    ("density[kg.m-2]", "areal_density", 1.0, True),
    ("linear warp[SI*1e9]", "rigidity_warp", 1e-9, True),
    ("linear weft[SI*1e9]", "rigidity_weft", 1e-9, True),
    ("linear diag[SI*1e9]", "rigidity_diagonal", 1e-9, True),
    ("nonlinear warp[SI*1e12]", "nonlinear_warp", 1e-12, False),
    ("nonlinear weft[SI*1e12]", "nonlinear_weft", 1e-12, False),
    ("nonlinear diag[SI*1e12]", "nonlinear_diagonal", 1e-12, False),
)
"""The file's columns in order: (header name, :class:`FabricRecord` field, factor to SI,
whether the value must be positive). The one place the file's units meet SI: kg/m² as
written; ``SI*1e9`` is k₁ in N·m times 10⁹, ``SI*1e12`` k₂ in N·m² times 10¹²."""


@dataclass(frozen=True)
class FabricRecord:
    """One fabric of the Feng et al. 2022 dataset, in SI.

    The moment per width along a direction is M(κ) = k₁ κ + k₂ κ² (N·m/m = N), κ in 1/m.
    """

    areal_density: float  # ρ_A, kg/m²
    rigidity_warp: float  # k₁ along the warp: bending rigidity per width B, N·m (N·m²/m)
    rigidity_weft: float  # k₁ along the weft, N·m
    rigidity_diagonal: float  # k₁ along the diagonal (45°, ArcSim's "bias"), N·m
    nonlinear_warp: float  # k₂ along the warp, N·m² (negative: softening)
    nonlinear_weft: float  # k₂ along the weft, N·m²
    nonlinear_diagonal: float  # k₂ along the diagonal, N·m²
    line: int  # 1-based line of the file the values were read from (the first, if repeated)
    copies: int = 1  # how many rows of the file hold exactly these seven numbers

    @property
    def bending_lengths(self) -> tuple[float, float, float]:
        """The linear model's bending length c = (k₁ / (ρ_A g))^{1/3} in m along the warp,
        the weft and the diagonal (:func:`bending_length`)."""
        return tuple(
            bending_length(b, self.areal_density)
            for b in (self.rigidity_warp, self.rigidity_weft, self.rigidity_diagonal)
        )


def read_feng2022(path: str | os.PathLike[str] | None = None, *, distinct: bool = True) -> list[FabricRecord]:
    """The fabrics of Feng et al. 2022's ``dataset/dataset.csv``, in SI, in file order.

    ``path``: the file (fetched from :data:`FENG2022_URL`; warpcloth does not bundle it);
    None reads the path from the environment variable :data:`FENG2022_ENV`. With
    ``distinct`` (the default) rows repeating the seven numbers of an earlier row exactly
    are folded into it (its ``copies`` counts them; the file at :data:`FENG2022_COMMIT` has
    618 rows, 251 distinct); without, every row is a record of its own.

    The header must name the seven columns of :data:`COLUMNS`, in order; every cell must
    be a finite number, the density and the three k₁ positive. A file that cannot be read
    is an :class:`~warpcloth.errors.ArgumentError` of ``path``; anything wrong inside it a
    :class:`~warpcloth.errors.DataFileError` naming the file, the line and the column.
    """
    if path is None:
        path = os.environ.get(FENG2022_ENV)
        if not path:
            raise ArgumentError(
                "path",
                f"no file given and {FENG2022_ENV} is not set; warpcloth does not bundle the Feng et al. 2022 "
                f"dataset (its repository grants no licence): fetch {FENG2022_FILE} from {FENG2022_URL} "
                f"and pass its path",
            )
    path = Path(path)
    try:
        text = read_text(path)
    except OSError as exc:
        raise ArgumentError("path", f"cannot read the Feng et al. 2022 dataset {path}: {exc.strerror}") from None
    rows = [(number, line.strip()) for number, line in enumerate(text.splitlines(), start=1)]
    rows = [(number, line) for number, line in rows if line and not line.startswith("#")]
    if not rows:
        raise DataFileError(path, "the file is empty; expected a header and one row per fabric")
    _check_header(path, *rows[0])
    records: list[FabricRecord] = []
    first: dict[tuple[float, ...], int] = {}
    for number, line in rows[1:]:
        values = _row(path, number, line)
        if distinct and values in first:
            i = first[values]
            records[i] = replace(records[i], copies=records[i].copies + 1)
            continue
        first[values] = len(records)
        fields = {field: value * factor for (_, field, factor, _), value in zip(COLUMNS, values, strict=True)}
        records.append(FabricRecord(**fields, line=number))
    if not records:
        raise DataFileError(path, "the file has a header but no fabric")
    return records


def _check_header(path: Path, number: int, line: str) -> None:
    # The header must name COLUMNS in order (the names as the file writes them).
    names = [cell.strip() for cell in line.split(",")]
    for column, (expected, _, _, _) in enumerate(COLUMNS, start=1):
        if column > len(names):
            raise DataFileError(path, f"column {column}: the header has no {expected!r} (it has {len(names)})", number)
        if names[column - 1] != expected:
            raise DataFileError(
                path, f"column {column}: the header says {names[column - 1]!r}, expected {expected!r}", number
            )
    if len(names) > len(COLUMNS):
        raise DataFileError(
            path, f"column {len(COLUMNS) + 1}: the header has {len(names)} columns, expected {len(COLUMNS)}", number
        )


def _row(path: Path, number: int, line: str) -> tuple[float, ...]:
    # The seven numbers of one data row, as written (the key rows are compared by).
    cells = [cell.strip() for cell in line.split(",")]
    if len(cells) != len(COLUMNS):
        if len(cells) < len(COLUMNS):
            what = f"column {len(cells) + 1}: {COLUMNS[len(cells)][0]} is missing"
        else:
            what = f"column {len(COLUMNS) + 1}: one past the last"
        raise DataFileError(path, f"{what} ({len(cells)} cells, expected {len(COLUMNS)})", number)
    values = []
    for column, (cell, (name, _, _, positive)) in enumerate(zip(cells, COLUMNS, strict=True), start=1):
        where = f"column {column} ({name})"
        try:
            value = float(cell)
        except ValueError:
            raise DataFileError(path, f"{where}: {cell!r} is not a number", number) from None
        if not math.isfinite(value):
            raise DataFileError(path, f"{where}: {cell!r} is not finite", number)
        if positive and value <= 0:
            raise DataFileError(path, f"{where}: {cell} is not positive", number)
        values.append(value)
    return tuple(values)


def bending_length(rigidity: float, areal_density: float, gravity: float = STANDARD_GRAVITY) -> float:
    """The bending length c = (B / (ρ_A g))^{1/3} in m of a fabric of bending rigidity per
    width ``rigidity`` B (N·m) and areal density ``areal_density`` ρ_A (kg/m²).

    A cantilever test reads c: a strip pushed over a ledge until its tip's chord makes
    41.5° with the horizontal overhangs by ℓ = 2c (Peirce; ASTM D1388, ISO 9073-7;
    :func:`bending_length_from_overhang`), and B = ρ_A g c³ (:func:`rigidity_from_bending_length`).
    """
    for argument, value, unit in (("rigidity", rigidity, "N·m"), ("areal_density", areal_density, "kg/m²")):
        _check_positive(argument, value, unit)
    return (rigidity / (areal_density * gravity)) ** (1.0 / 3.0)


def rigidity_from_bending_length(
    bending_length: float, areal_density: float, gravity: float = STANDARD_GRAVITY
) -> float:
    """The bending rigidity per width B = ρ_A g c³ in N·m of a fabric whose cantilever test
    read a bending length ``bending_length`` c (m), of areal density ``areal_density`` ρ_A
    (kg/m²): the SI form of the textile flexural rigidity G = W c³."""
    for argument, value, unit in (("bending_length", bending_length, "m"), ("areal_density", areal_density, "kg/m²")):
        _check_positive(argument, value, unit)
    return areal_density * gravity * bending_length**3


def bending_length_from_overhang(overhang: float) -> float:
    """The bending length c = ℓ/2 in m of a strip whose fixed-angle cantilever test (tip
    chord at 41.5° below the horizontal) read an overhang ``overhang`` ℓ (m).

    The exact heavy elastica of length 2c has its chord at 41.49° (tests/test_elastica.py);
    Peirce's closed form c = ℓ (cos(θ/2) / (8 tan θ))^{1/3}, an approximation, gives 0.509 ℓ
    at θ = 41.5°.
    """
    for argument, value, unit in (("overhang", overhang, "m"),):
        _check_positive(argument, value, unit)
    return overhang / 2.0


def _check_positive(argument: str, value: float, unit: str) -> None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not (math.isfinite(number) and number > 0):
        raise ArgumentError(argument, f"must be a finite number > 0 {unit}, got {value!r}")
