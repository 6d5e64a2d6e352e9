"""The one reader of instrument files: laser traces, tracked markers and clamp encoders
(:mod:`warpcloth.io.measured`), KES-FB1/FB2 loops (:mod:`warpcloth.calibrate.kes`).

A file is a table of numbers, one row per line, as lab software or a spreadsheet
writes it:

- **Encoding:** UTF-8 (a spreadsheet's byte-order mark dropped), else Latin-1, as
  instrument software on Windows writes it; the numbers are ASCII either way.
- **Comments, blank lines:** ``#`` starts a comment that runs to the end of its line;
  blank lines are skipped. Line numbers in messages count every line of the file from 1.
- **Header:** the first line that is not blank or a comment is a header when its first
  cell is not a number; its names may contain spaces unless whitespace separates them.
- **Delimiter**, one per file, taken from the first data row: ``;`` if the row has one,
  else a tab, else ``,``, else runs of whitespace. A row whose ``,``-separated cells
  themselves contain whitespace (``1,5 2,5``) is whitespace-separated with decimal
  commas. A trailing delimiter, as spreadsheets write, is ignored.
- **Decimal comma:** with ``;`` a ``,`` in a number is a decimal comma (``0,5``), as
  spreadsheets in decimal-comma locales write; with a tab or whitespace it is one only
  when no number in the file has a decimal point, so the file cannot mean anything else
  (a ``,`` and a ``.`` in one such file are refused, naming the lines); with ``,``
  separating the columns there is no decimal comma.
- **Cells:** each is a number in Python's syntax (``-1.5``, ``2e-3``) and finite; a cell
  that is empty, not a number or not finite is reported with the file and its line.
"""

from __future__ import annotations

import difflib
import importlib.resources
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError, DataFileError

WHITESPACE = " "
"""The delimiter value that stands for runs of whitespace (spaces and tabs mixed)."""

DELIMITERS = (";", "\t", ",", WHITESPACE)
"""The delimiters a file may use, in the order they are looked for in its first data row."""


@dataclass(frozen=True)
class Table:
    """The numbers of a data file, the lines they came from, and how the file was read."""

    path: Path  # the file read (a bundled example resolved to its location)
    values: np.ndarray  # [row, column] float64, every value finite
    lines: np.ndarray  # 1-based file line of each row
    header: list[str] | None  # the header's names as written (stripped); None without a header
    header_line: int | None  # 1-based file line of the header
    header_text: str | None  # the header line as written (stripped, comment removed)
    delimiter: str  # one of DELIMITERS
    decimal_comma: bool  # whether a "," in a number was read as the decimal separator


def bundled_data(name: str | Path) -> Path:
    """``name`` itself if it is a file, else the bundled example of that name
    (``damped_swing_laser`` or ``damped_swing_laser.csv``, from scenes/data/)."""
    path = Path(name)
    if path.is_file() or "/" in str(name) or "\\" in str(name):
        return path  # a path is a path (./laser.csv that is missing is an error, not the bundled one)
    resource = importlib.resources.files("warpcloth.scenes") / "data" / (path.stem + ".csv")
    return Path(str(resource)) if path.parent == Path(".") and resource.is_file() else path


def bundled_data_names() -> list[str]:
    """The names of the bundled example data files (``scenes/data/*.csv``, without ``.csv``)."""
    folder = importlib.resources.files("warpcloth.scenes") / "data"
    return sorted(entry.name[:-4] for entry in folder.iterdir() if entry.name.endswith(".csv"))


def _missing(name: str | Path) -> str:
    # a bare name (no folder in it) that is neither a file here nor bundled was most likely
    # a bundled one misspelt
    if "/" in str(name) or "\\" in str(name) or Path(name).exists():
        return ""
    names = bundled_data_names()
    close = difflib.get_close_matches(Path(name).stem, names, n=1)
    hint = f"; did you mean {close[0]}?" if close else ""
    return f"{hint} (bundled: {', '.join(names)}; a file of your own is a path)"


def read_text(path: Path) -> str:
    """A data file's text: UTF-8 (a spreadsheet's byte-order mark dropped), else Latin-1,
    as instrument software on Windows writes it; the numbers are ASCII either way."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _line_delimiter(text: str) -> str:
    # The delimiter a single row uses (see the module docstring).
    if ";" in text:
        return ";"
    if "\t" in text:
        return "\t"
    if "," in text:
        return WHITESPACE if any(len(cell.split()) > 1 for cell in text.split(",")) else ","
    return WHITESPACE


def _split(text: str, delimiter: str) -> list[str]:
    if delimiter == WHITESPACE:
        return text.split()
    cells = [cell.strip() for cell in text.split(delimiter)]
    while cells and not cells[-1]:
        cells.pop()  # a trailing delimiter, as spreadsheets write
    return cells


def _number(cell: str) -> float | None:
    try:
        return float(cell)
    except ValueError:
        return None


def _content(lines: list[str]) -> list[tuple[int, str]]:
    # (1-based line number, text without comment and surrounding whitespace) of each
    # line that holds anything.
    out = []
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if text:
            out.append((number, text))
    return out


def read_csv(
    path: str | Path,
    columns: int | None = None,
    *,
    what: str = "data",
    names: Sequence[str] | None = None,
    extra_columns: bool = False,
    argument: str | None = None,
) -> Table:
    """Read a table of numbers from a CSV-like file (or a bundled example by name).

    ``columns``: how many columns every row has (None: as many as the first data row);
    with ``extra_columns`` a row may have more, and they are ignored. ``what`` names the
    kind of file and ``names`` its columns in messages. A file that cannot be read is an
    ArgumentError of ``argument`` when one supplied it (the caller's name for ``path``),
    else a DataFileError; anything
    wrong inside the file is a DataFileError naming the file and the line.
    """
    named, path = path, bundled_data(path)
    try:
        lines = read_text(path).splitlines()
    except OSError as exc:
        reason = f"{exc.strerror}{_missing(named)}"
        if argument is not None:
            raise ArgumentError(argument, f"cannot read the {what} file {path}: {reason}") from None
        raise DataFileError(path, f"cannot read the {what} file: {reason}") from None
    content = _content(lines)
    header = header_line = header_text = None
    if content:
        number, text = content[0]
        cells = _split(text, _line_delimiter(text))
        first = cells[0] if cells else ""
        if _number(first) is None and _number(first.replace(",", ".")) is None:
            header_line, header_text = number, text
            content = content[1:]
    delimiter = _line_delimiter(content[0][1] if content else header_text or "")
    if header_text is not None:
        own = delimiter if delimiter == WHITESPACE or delimiter in header_text else _line_delimiter(header_text)
        header = _split(header_text, own)
    rows = [(number, text, _split(text, delimiter)) for number, text in content]
    decimal_comma = _decimal_comma(path, rows, delimiter)
    if columns is None:
        columns = len(rows[0][2]) if rows else 0
    described = f" (a {what} file has {', '.join(names)})" if names else ""
    values = np.empty((len(rows), columns), dtype=np.float64)
    for i, (number, text, cells) in enumerate(rows):
        if len(cells) < columns or (len(cells) > columns and not extra_columns):
            raise DataFileError(path, f"expected {columns} columns, got {len(cells)}: {text!r}{described}", number)
        for j, cell in enumerate(cells[:columns]):
            value = _number(cell.replace(",", ".") if decimal_comma else cell)
            if value is None:
                raise DataFileError(
                    path, f"column {j + 1} is empty" if not cell else f"{cell!r} is not a number", number
                )
            if not math.isfinite(value):
                name = names[j] if names and j < len(names) else f"column {j + 1}"
                raise DataFileError(path, f"{name} is {value}; every value must be finite", number)
            values[i, j] = value
    return Table(
        path,
        values,
        np.array([number for number, _, _ in rows], dtype=int),
        header,
        header_line,
        header_text,
        delimiter,
        decimal_comma,
    )


def _decimal_comma(path: Path, rows: list[tuple[int, str, list[str]]], delimiter: str) -> bool:
    # Whether a "," in a cell is a decimal comma (see the module docstring).
    if delimiter == ";":
        return True
    if delimiter == ",":
        return False
    comma = next((number for number, _, cells in rows if any("," in c for c in cells)), None)
    if comma is None:
        return False
    point = next((number for number, _, cells in rows if any("." in c for c in cells)), None)
    if point is not None:
        between = "tabs" if delimiter == "\t" else "whitespace"
        raise DataFileError(
            path,
            f"a decimal comma, but line {point} has a decimal point: with {between} "
            "between the columns a file "
            "uses one or the other (or separate the columns with ';' and use decimal commas)",
            comma,
        )
    return True
