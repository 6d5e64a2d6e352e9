"""Where a scene field got its value: the override that set it, or the file and line.

A SceneError names the field; this adds where to change it, so that a refusal of
``integrator.dt_s`` says ``damped_swing.toml, line 32`` or ``set by the override
integrator.dt_s=1e-4``. TOML parsers keep no line numbers, so the lines come from a scan
of the text that knows tables, arrays of tables (nested too), quoted and dotted keys and
multi-line strings; a value written inside a multi-line array or an inline table is
placed at the line of its key. A field nobody set (a default, or a value a material file
gave) is left unlocated rather than pinned on the wrong line.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from typing import Any

from warpcloth.errors import SceneError

from .materials import MATERIAL_FILE_KEY
from .overrides import Overrides, key_path, override_pairs

_BARE_OR_QUOTED = r"""(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')"""
_DOTTED = rf"{_BARE_OR_QUOTED}(?:\s*\.\s*{_BARE_OR_QUOTED})*"
_HEADER = re.compile(rf"^\s*(\[\[|\[)\s*({_DOTTED})\s*\]")
_KEY = re.compile(rf"^\s*({_DOTTED})\s*=\s*(.*)$")


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
    of); with ``swept``, the line of a ``[sweep...]`` table that varies it instead."""
    target = key_path(field)
    best, best_length = None, 0
    for path, number in toml_keys(text):
        if swept:
            if path[0] == "sweep" and key_path(path[-1]) == target:
                return number
            continue
        if path[:len(target)] == target:
            return number  # the field itself, or a table of it written with dotted keys
        if len(path) > best_length and target[:len(path)] == path:
            best, best_length = number, len(path)  # the value sits inside this key's array or inline table
    return best


def _written(value: Any) -> str:
    """A Python override value as TOML writes it (no numpy reprs in a message)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_written(v) for v in value) + "]"
    return repr(float(value)) if isinstance(value, float) else str(value)


def _overlaps(a: tuple[str, ...], b: tuple[str, ...]) -> bool:
    shorter = min(len(a), len(b))
    return a[:shorter] == b[:shorter]


def where_set(error: SceneError, text: str | None, source: str, overrides: Overrides = ()) -> str | None:
    """Where the value behind ``error`` was set: for a sweep variant the line that sweeps
    it; else the override last applied to its field (a ``material.from_file`` override
    counts for every material field), then to a field its check read; else ``source, line
    N`` of the scene ``text``; None when nothing names it."""
    if isinstance(overrides, Mapping):
        written = [(key, f"{key}={_written(value)}") for key, value in overrides.items()]
    else:
        items = list(overrides)
        written = [(key, item.strip()) for (key, _value), item in zip(override_pairs(items), items, strict=True)]
    # the order apply_overrides applies them in: the material file first, then as given
    written.sort(key=lambda pair: pair[0] != MATERIAL_FILE_KEY)
    fields = [key_path(f) for f in (error.field, *error.related)]
    if error.variant is not None and text is not None:
        for field in (error.field, *error.related):
            if line := field_line(text, field, swept=True):
                return f"{source}, line {line}"

    def sets(key: str, path: tuple[str, ...]) -> bool:
        return _overlaps(key_path(key), path) or (key == MATERIAL_FILE_KEY and path[0] == "material")

    for candidates in (fields[:1], fields[1:]):
        for key, item in reversed(written):  # the last one applied wins
            if any(sets(key, path) for path in candidates):
                return f"set by the override {item}"
    line = field_line(text, error.field) if text is not None else None
    return f"{source}, line {line}" if line is not None else None


def located(error: SceneError, text: str | None, source: str, overrides: Overrides = ()) -> SceneError:
    """``error`` with where its value was set appended, or ``error`` itself if unknown."""
    where = where_set(error, text, source, overrides)
    if where is None:
        return error
    return SceneError(error.field, f"{error.message} ({where})", error.related, error.variant)
