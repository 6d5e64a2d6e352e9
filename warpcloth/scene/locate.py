"""Where a scene field got its value: the override that set it, or the file and line.

A SceneError names the field; this adds where to change it, so that a refusal of
``integrator.dt_s`` says ``damped_swing.toml, line 32`` or ``set by the override
integrator.dt_s=1e-4`` (the lines come from :mod:`.keys`). A field nobody set (a
default, or a value a material file gave) is left unlocated rather than pinned on the
wrong line.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from warpcloth.errors import SceneError

from .keys import field_line, is_material_file_key, key_path_or_none, overlaps
from .overrides import Overrides, override_pairs


def _written(value: Any) -> str:
    """A Python override value as TOML writes it (no numpy reprs in a message)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_written(v) for v in value) + "]"
    return repr(float(value)) if isinstance(value, float) else str(value)


def where_set(error: SceneError, text: str | None, source: str, overrides: Overrides = ()) -> str | None:
    """Where the value behind ``error`` was set, or None when nothing names it.

    For a sweep variant: the override of its swept entry, else the file's [sweep] line.
    Otherwise the override last applied to the error's field (a ``material.from_file``
    override counts for every material field), else the field's line in the scene
    ``text``, followed by any override of a field the check also read.
    """
    if isinstance(overrides, Mapping):
        written = [(str(key), f"{key}={_written(value)}") for key, value in overrides.items()]
    else:
        items = list(overrides)
        written = [(key, item.strip()) for (key, _value), item in zip(override_pairs(items), items, strict=True)]
    # the order apply_overrides applies them in: the material file first, then as given
    written.sort(key=lambda pair: not is_material_file_key(pair[0]))
    own, others = key_path_or_none(error.field), [key_path_or_none(f) for f in error.related]

    def last(matches: object) -> str | None:
        found = [item for key, item in written if matches(key_path_or_none(key), key)]
        return found[-1] if found else None

    if error.variant is not None:
        for name in (error.field, *error.related):
            field = key_path_or_none(name)
            swept = last(
                lambda path, _key, field=field: (
                    len(path) > 2 and path[0] == "sweep" and key_path_or_none(path[-1]) == field
                )
            )
            if swept:
                return f"set by the override {swept}"
            line = field_line(text, name, swept=True) if text is not None else None
            if line:
                return f"{source}, line {line}"
    related = last(
        lambda path, key: (
            any(overlaps(path, f) for f in others)
            or (is_material_file_key(key) and any(f[:1] == ("material",) for f in others))
        )
    )
    mine = last(lambda path, key: overlaps(path, own) or (is_material_file_key(key) and own[:1] == ("material",)))
    if mine:
        return f"set by the override {mine}"
    line = field_line(text, error.field) if text is not None else None
    if line is not None:
        return f"{source}, line {line}" + (f"; and the override {related}" if related else "")
    return f"set by the override {related}" if related else None


def located(error: SceneError, text: str | None, source: str, overrides: Overrides = ()) -> SceneError:
    """``error`` with where its value was set appended, or ``error`` itself if unknown."""
    where = where_set(error, text, source, overrides)
    if where is None:
        return error
    return SceneError(error.field, f"{error.message} ({where})", error.related, error.variant)


def variant_error(error: SceneError, variant: int, assignment: dict) -> SceneError:
    """``error`` of sweep variant ``variant``, saying which values it was given."""
    what = ", ".join(f"{k}={v!r}" for k, v in assignment.items())
    return SceneError(error.field, f"in sweep variant {variant} ({what}): {error.message}", error.related, variant)
