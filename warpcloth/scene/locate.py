"""Where a scene field got its value: the override that set it, or the file and line.

A SceneError names the field; this adds where to change it, so that a refusal of
``integrator.dt_s`` says ``damped_swing.toml, line 32`` or ``the override
integrator.dt_s=1e-4``. TOML parsers keep no line numbers, so the lines come from a scan
of the text that knows tables, arrays of tables and (quoted, dotted) keys: enough for
scene files, and a field it cannot place is simply left unlocated.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping

from warpcloth.errors import SceneError

from .overrides import Overrides

_BARE_OR_QUOTED = r"""(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')"""
_HEADER = re.compile(rf"^\s*(\[\[|\[)\s*({_BARE_OR_QUOTED}(?:\s*\.\s*{_BARE_OR_QUOTED})*)\s*\]")
_KEY = re.compile(rf"^\s*({_BARE_OR_QUOTED}(?:\s*\.\s*{_BARE_OR_QUOTED})*)\s*=")
_PART = re.compile(r""""([^"]*)"|'([^']*)'|([A-Za-z0-9_-]+)""")


def key_path(dotted: str) -> tuple[str, ...]:
    """``clamp.segments[1].t_end_s``, ``clamp.segments.1.t_end_s`` and
    ``sweep.grid."damping.gamma_per_s"`` as tuples of keys (list items by index)."""
    dotted = re.sub(r"\[(\d+)\]", r".\1", dotted)
    return tuple(a or b or c for a, b, c in _PART.findall(dotted))


def toml_keys(text: str) -> Iterator[tuple[tuple[str, ...], int]]:
    """The full key path and 1-based line of every ``key = value`` in TOML ``text``."""
    table: tuple[str, ...] = ()
    entries: dict[tuple[str, ...], int] = {}
    for number, line in enumerate(text.splitlines(), 1):
        if header := _HEADER.match(line):
            table = key_path(header.group(2))
            if header.group(1) == "[[":
                entries[table] = entries.get(table, -1) + 1
                table = (*table, str(entries[table]))
        elif key := _KEY.match(line):
            yield (*table, *key_path(key.group(1))), number


def field_line(text: str, field: str, swept: bool = False) -> int | None:
    """The line of ``text`` that sets scene ``field``; with ``swept``, a line of a
    ``[sweep...]`` table that varies it is preferred (a sweep variant's value came from
    there)."""
    target = key_path(field)
    plain = None
    for path, number in toml_keys(text):
        if swept and path[0] == "sweep" and path[-1] == ".".join(target):
            return number
        if plain is None and path == target:
            plain = number
    return plain


def where_set(field: str, text: str | None, source: str, overrides: Overrides = (), swept: bool = False) -> str | None:
    """Where ``field`` was set: the override naming it, else ``source, line N`` of the scene
    ``text``; None when neither sets it (a default, or a value from a material file)."""
    target = key_path(field)
    items = overrides.items() if isinstance(overrides, Mapping) else ((None, item) for item in overrides)
    for key, item in items:
        written = f"{key}={item!r}" if key is not None else str(item)
        if key_path(written.split("=", 1)[0]) == target:
            return f"set by the override {written}"
    line = field_line(text, field, swept) if text is not None else None
    return f"{source}, line {line}" if line is not None else None


def located(error: SceneError, text: str | None, source: str, overrides: Overrides = (),
            swept: bool = False) -> SceneError:
    """``error`` with where its field was set appended, or ``error`` itself if unknown."""
    where = where_set(error.field, text, source, overrides, swept)
    return error if where is None else SceneError(error.field, f"{error.message} ({where})")
