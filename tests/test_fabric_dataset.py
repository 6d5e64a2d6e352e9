"""The reader of Feng et al. 2022's real-fabric dataset (warpcloth.calibrate.fabric_dataset).

The dataset is not bundled (its repository grants no licence): the tests that need the file
itself read it from WARPCLOTH_FENG2022_CSV (dataset/dataset.csv of
https://github.com/DrapeTester/ClothDrapeTester at commit 24a980c) and skip without it; the
rest read a small file written here in the same format.
"""

import hashlib
import math
import os
from pathlib import Path

import numpy as np
import pytest

from warpcloth.calibrate import fabric_dataset as fd
from warpcloth.errors import ArgumentError, DataFileError

FILE = os.environ.get(fd.FENG2022_ENV)
needs_file = pytest.mark.skipif(
    not (FILE and Path(FILE).is_file()), reason=f"{fd.FENG2022_ENV} does not name the Feng et al. 2022 dataset"
)

HEADER = (
    "density[kg.m-2], linear warp[SI*1e9], linear weft[SI*1e9], linear diag[SI*1e9], "
    "nonlinear warp[SI*1e12], nonlinear weft[SI*1e12], nonlinear diag[SI*1e12]"
)
SYNTHETIC = "\n".join(
    [
        HEADER,
        "0.1000, 2000.0, 1000.0, 1200.0, -5000.0, -3000.0, -2000.0",
        "0.2500, 40000.0, 30000.0, 9000.0, -90000.0, -60000.0, 1500.0",
        "0.1000, 2000.0, 1000.0, 1200.0, -5000.0, -3000.0, -2000.0",
        "0.0500, 800.0, 900.0, 1000.0, -1000.0, -1000.0, -1000.0",
    ]
)
"""A file in the dataset's format with made-up numbers: 4 rows, 3 distinct (lines 2 and 4 alike)."""


@pytest.fixture
def synthetic(tmp_path):
    path = tmp_path / "dataset.csv"
    path.write_text(SYNTHETIC)
    return path


@pytest.fixture
def original():
    """The text of the real file when the environment names it, else of the synthetic one."""
    return Path(FILE).read_text() if FILE and Path(FILE).is_file() else SYNTHETIC


def _damaged(tmp_path, text, line, column, cell):
    # ``text`` with the cell of ``column`` (1-based) on ``line`` (1-based) replaced by
    # ``cell``, or removed when ``cell`` is None
    lines = text.splitlines()
    cells = lines[line - 1].split(",")
    if cell is None:
        del cells[column - 1]
    else:
        cells[column - 1] = " " + cell
    lines[line - 1] = ",".join(cells)
    path = tmp_path / "damaged.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


# --- the file itself --------------------------------------------------------------------


@needs_file
def test_the_file_is_the_one_the_reader_was_written_against():
    assert hashlib.sha256(Path(FILE).read_bytes()).hexdigest() == fd.FENG2022_SHA256


@needs_file
def test_the_reader_gives_the_distinct_rows():
    records = fd.read_feng2022(FILE)
    assert len(records) == 251  # of 618 rows, as the issue says
    assert sum(r.copies for r in records) == 618
    assert len(fd.read_feng2022(FILE, distinct=False)) == 618
    # folding on (density, warp, weft, diagonal) alone folds the same rows: no two fabrics
    # share those four numbers and differ in k₂
    linear = {(r.areal_density, r.rigidity_warp, r.rigidity_weft, r.rigidity_diagonal) for r in records}
    assert len(linear) == 251
    assert [r.line for r in records] == sorted(r.line for r in records)  # file order, first occurrence


@needs_file
def test_the_first_row_converts_as_by_hand(monkeypatch):
    # dataset.csv line 2: 0.0673, 1779.9, 3076.2, 2244.1, -8478.2, -4158.5, -3351.1
    raw = [float(cell) for cell in Path(FILE).read_text().splitlines()[1].split(",")]
    assert raw == [0.0673, 1779.9, 3076.2, 2244.1, -8478.2, -4158.5, -3351.1]
    monkeypatch.setenv(fd.FENG2022_ENV, FILE)
    first = fd.read_feng2022()[0]  # path from the environment
    assert first.line == 2 and first.copies == 2
    assert first.areal_density == 0.0673  # kg/m², as written
    assert first.rigidity_warp == pytest.approx(1.7799e-6, rel=1e-12)  # 1779.9e-9 N·m
    assert first.rigidity_weft == pytest.approx(3.0762e-6, rel=1e-12)
    assert first.rigidity_diagonal == pytest.approx(2.2441e-6, rel=1e-12)
    assert first.nonlinear_warp == pytest.approx(-8.4782e-9, rel=1e-12)  # -8478.2e-12 N·m²
    assert first.nonlinear_weft == pytest.approx(-4.1585e-9, rel=1e-12)
    assert first.nonlinear_diagonal == pytest.approx(-3.3511e-9, rel=1e-12)
    # c = (1.7799e-6 N·m / (0.0673 kg/m² × 9.80665 m/s²))^(1/3) = (2.69687e-6 m³)^(1/3) = 13.919 mm
    assert first.bending_lengths[0] == pytest.approx(0.013919, rel=1e-4)


@needs_file
def test_the_diagonal_against_warp_and_weft():
    # The issue: diagonal k₁ over the mean of warp and weft has median about 0.89
    # (10–90 %: 0.49–1.58), and only about 11 % of fabrics lie below (warp + weft)/4.
    records = fd.read_feng2022(FILE)
    warp = np.array([r.rigidity_warp for r in records])
    weft = np.array([r.rigidity_weft for r in records])
    diagonal = np.array([r.rigidity_diagonal for r in records])
    ratio = diagonal / ((warp + weft) / 2)
    assert np.median(ratio) == pytest.approx(0.89, abs=0.005)  # measured 0.8926
    low, high = np.percentile(ratio, [10, 90])
    assert low == pytest.approx(0.49, abs=0.005)  # measured 0.4941
    assert high == pytest.approx(1.58, abs=0.005)  # measured 1.5845
    below = int(np.sum(diagonal < (warp + weft) / 4))
    assert below == 27 and below / len(records) == pytest.approx(0.11, abs=0.005)  # 10.8 %


# --- the reader, on a file written here ---------------------------------------------------


def test_a_file_in_the_format_is_read_and_folded(synthetic):
    records = fd.read_feng2022(synthetic)
    assert [(r.line, r.copies) for r in records] == [(2, 2), (3, 1), (5, 1)]
    second = records[1]
    assert second.areal_density == 0.25
    assert (second.rigidity_warp, second.rigidity_weft, second.rigidity_diagonal) == pytest.approx((4e-5, 3e-5, 9e-6))
    assert second.nonlinear_diagonal == pytest.approx(1.5e-9)  # a positive k₂ is kept as written
    c = (4e-5 / (0.25 * 9.80665)) ** (1 / 3)
    assert second.bending_lengths[0] == pytest.approx(c)
    assert [r.line for r in fd.read_feng2022(synthetic, distinct=False)] == [2, 3, 4, 5]


@pytest.mark.parametrize(
    ("line", "column", "cell", "message"),
    [
        (5, 3, "abc", "column 3 (linear weft[SI*1e9]): 'abc' is not a number"),
        (5, 2, "-1779.9", "column 2 (linear warp[SI*1e9]): -1779.9 is not positive"),
        (5, 1, "0", "column 1 (density[kg.m-2]): 0 is not positive"),
        (5, 6, "nan", "column 6 (nonlinear weft[SI*1e12]): 'nan' is not finite"),
        (5, 7, "", "column 7 (nonlinear diag[SI*1e12]): '' is not a number"),
        (5, 4, None, "column 7: nonlinear diag[SI*1e12] is missing (6 cells, expected 7)"),
        (1, 3, None, "column 3: the header says 'linear diag[SI*1e9]', expected 'linear weft[SI*1e9]'"),
    ],
)
def test_a_damaged_copy_is_refused_naming_line_and_column(tmp_path, original, line, column, cell, message):
    path = _damaged(tmp_path, original, line, column, cell)
    with pytest.raises(DataFileError) as raised:
        fd.read_feng2022(path)
    assert str(raised.value) == f"{path}, line {line}: {message}"
    assert raised.value.line == line


def test_without_a_file_the_reader_says_where_to_get_one(monkeypatch, tmp_path):
    monkeypatch.delenv(fd.FENG2022_ENV, raising=False)
    with pytest.raises(ArgumentError, match="^path: no file given and WARPCLOTH_FENG2022_CSV is not set") as raised:
        fd.read_feng2022()
    assert fd.FENG2022_URL in str(raised.value) and raised.value.argument == "path"
    with pytest.raises(ArgumentError, match="^path: cannot read the Feng et al. 2022 dataset .*missing.csv"):
        fd.read_feng2022(tmp_path / "missing.csv")


# --- bending length -----------------------------------------------------------------------


def test_bending_length_and_rigidity_are_inverse():
    c = fd.bending_length(1.7799e-6, 0.0673)
    assert fd.rigidity_from_bending_length(c, 0.0673) == pytest.approx(1.7799e-6, rel=1e-12)
    # Peirce's fixed-angle test: ℓ = 2c at 41.5°; his closed form gives 0.509 ℓ there
    assert fd.bending_length_from_overhang(0.05) == 0.025
    theta = math.radians(41.5)
    assert (math.cos(theta / 2) / (8 * math.tan(theta))) ** (1 / 3) == pytest.approx(0.509, abs=5e-4)
    with pytest.raises(ArgumentError, match=r"^areal_density: must be a finite number > 0 kg/m², got -1\.0$"):
        fd.bending_length(1e-6, -1.0)
    with pytest.raises(ArgumentError, match="^overhang: "):
        fd.bending_length_from_overhang(float("nan"))
