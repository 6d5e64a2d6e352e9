"""Dotted scene field names, and the lines of TOML text that set them.

One grammar for every dotted name (``--set`` keys, sweep entries, error fields): parts of
letters, digits, ``_`` and ``-``, joined by dots; a list item as ``.N`` or ``[N]``; a
part in quotes kept whole, dots and all (a swept field's name under ``sweep.grid``,
``sweep.zip`` or ``sweep.random.ranges``). TOML parsers keep no line numbers, so
:func:`field_line` scans the text: tables, arrays of tables (nested too), quoted and
dotted keys, multi-line strings; a value inside a multi-line array or an inline table is
placed at the line of its key.
"""

from __future__ import annotations

import re
from collections.abc import Iterator

from warpcloth.errors import SceneError

_BARE = r"[A-Za-z0-9_-]+"
_QUOTED = r""""[^"]*"|'[^']*'"""
_PART = rf"(?:{_BARE}|{_QUOTED})"
_NAME = re.compile(rf"\s*{_PART}(?:\s*\.\s*{_PART}|\s*\[\d+\])*\s*")
_TOKEN = re.compile(rf"({_QUOTED})|\[(\d+)\]|({_BARE})")
_DOTTED = rf"{_PART}(?:\s*\.\s*{_PART})*"
_HEADER = re.compile(rf"^\s*(\[\[|\[)\s*({_DOTTED})\s*\]")
_KEY = re.compile(rf"^\s*({_DOTTED})\s*=\s*(.*)$")
SWEPT_NAME_TABLES = (("sweep", "grid"), ("sweep", "zip"), ("sweep", "random", "ranges"))
"""Where a quoted part may hold dots: a swept field's name."""
MATERIAL_FILE = ("material", "from_file")


def key_path(dotted: str) -> tuple[str, ...]:
    """``dotted`` as its keys (``clamp.segments[1].t_end_s`` and ``clamp.segments.1.t_end_s``
    alike; ``sweep.grid."damping.gamma_per_s"`` keeps the quoted name whole). A name
    outside the grammar (an empty part, a stray character) is a SceneError naming it."""
    text = str(dotted)
    if not _NAME.fullmatch(text):
        raise SceneError(
            text.strip() or repr(text),
            "is not a field name: dotted parts of letters, digits, _ and "
            "-, list items as .N or [N] (e.g. damping.gamma_per_s, clamp.segments.1.t_end_s)",
        )
    return tuple(quoted[1:-1] if quoted else index or bare for quoted, index, bare in _TOKEN.findall(text))


def key_path_or_none(dotted: object) -> tuple[str, ...]:
    """:func:`key_path` of ``str(dotted)``, or ``()`` where it is not a field name (for
    looking a name up, where a malformed one simply matches nothing)."""
    try:
        return key_path(str(dotted))
    except SceneError:
        return ()


def overlaps(a: tuple[str, ...], b: tuple[str, ...]) -> bool:
    """Whether one key path is the other or lies inside it (a list and one of its items)."""
    shorter = min(len(a), len(b))
    return shorter > 0 and a[:shorter] == b[:shorter]


def is_material_file_key(dotted: str) -> bool:
    """Whether ``dotted`` names ``material.from_file`` (however it is spelled)."""
    return key_path_or_none(dotted) == MATERIAL_FILE


def _opens_multiline_string(value: str) -> str | None:
    """The delimiter of a multi-line string the value starts and does not close."""
    for quote in ('"""', "'''"):
        if value.startswith(quote) and value.count(quote) % 2 == 1:
            return quote
    return None


def toml_keys(text: str) -> Iterator[tuple[tuple[str, ...], int]]:
    """The full key path (array-of-tables entries by index) and 1-based line of every
    ``key = value`` in TOML ``text``."""
    table: tuple[str, ...] = ()
    arrays: dict[tuple[str, ...], int] = {}  # each array of tables' current index, by its full path
    open_string = None
    for number, line in enumerate(text.split("\n"), 1):  # TOML's newlines only, not U+2028 and kin
        if open_string:
            if line.count(open_string) % 2 == 1:
                open_string = None
            continue
        if header := _HEADER.match(line):
            keys, table = key_path(header.group(2)), ()
            for key in keys[:-1]:  # a parent that is an array of tables means its current entry
                table = (*table, key)
                if table in arrays:
                    table = (*table, str(arrays[table]))
            table = (*table, keys[-1])
            if header.group(1) == "[[":
                arrays[table] = arrays.get(table, -1) + 1
                table = (*table, str(arrays[table]))
        elif key := _KEY.match(line):
            yield (*table, *key_path(key.group(1))), number
            open_string = _opens_multiline_string(key.group(2).strip())


def field_line(text: str, field: str, swept: bool = False) -> int | None:
    """The line of ``text`` that sets scene ``field`` (or the array or table it is an item
    of); with ``swept``, the line of a ``[sweep...]`` table that varies it instead. None
    where no line does (or ``field`` is not a field name)."""
    target = key_path_or_none(field)
    if not target:
        return None
    best, best_length = None, 0
    for path, number in toml_keys(text):
        if swept:
            if path[0] == "sweep" and key_path_or_none(path[-1]) == target:
                return number
            continue
        if path[: len(target)] == target:
            return number  # the field itself, or a table of it written with dotted keys
        if len(path) > best_length and target[: len(path)] == path:
            best, best_length = number, len(path)  # the value sits inside this key's array or inline table
    return best
