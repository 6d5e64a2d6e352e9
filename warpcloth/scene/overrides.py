"""``--set`` overrides: one dotted-name grammar for the command line, sweeps and fits."""

from __future__ import annotations

import copy
import tomllib
import typing
from pathlib import Path
from typing import Any

from warpcloth.errors import ArgumentTypeError, SceneError

from .keys import MATERIAL_FILE, SWEPT_NAME_TABLES, is_material_file_key, key_path
from .materials import MATERIAL_FILE_KEY, bundled_materials, material_fields, with_material_file


def _parse_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # a bare word such as forward or float32


def set_field(data: dict, key: str, value: Any) -> None:
    """Set the field ``key`` (dotted; list items by index) of raw scene ``data`` in place.

    Setting ``material.from_file`` selects that material: the [material] values already in
    ``data`` are dropped so that the file supplies them (set other material fields after it).
    """
    parts = list(key_path(key))
    for i, part in enumerate(parts):
        if "." in part and tuple(parts[:i]) not in SWEPT_NAME_TABLES:
            raise SceneError(
                key.strip(),
                f"{part!r} in quotes is a swept field's name, which only "
                f"{', '.join('.'.join(t) for t in SWEPT_NAME_TABLES)} take; elsewhere write it unquoted",
            )
    if tuple(parts) == MATERIAL_FILE:
        if not isinstance(value, str) or not value.strip():
            raise SceneError(
                MATERIAL_FILE_KEY,
                f"{value!r} names no material file; give a bundled material name "
                f"({', '.join(bundled_materials())}) or a path ending in .toml",
            )
        if value.endswith(".toml") and not Path(value).is_absolute():
            value = str(Path(value).resolve())  # relative to where the command runs, recorded absolute
        if isinstance(data.get("material"), dict):
            data["material"] = {
                k: v for k, v in data["material"].items() if k not in [*material_fields(), "bending_law"]
            }
    elif parts[0] == "material" and len(parts) > 2:
        # A list item of a material that comes from a file: the file's list first.
        data.update(with_material_file(data))
    node: Any = data
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise SceneError(".".join(parts[: i + 1]), f"no list item {part!r}")
            if last:
                node[int(part)] = value
            else:
                node = node[int(part)]
                if not isinstance(node, (dict, list)):
                    raise SceneError(".".join(parts[: i + 1]), "is a value, not a section")
        elif last:
            node[part] = value
        else:
            if part not in node and parts[i + 1].isdigit():
                raise SceneError(
                    ".".join(parts[: i + 1]),
                    f"has no list item {parts[i + 1]!r}: it is not set here (set the whole list, e.g. key=[...])",
                )
            node = node.setdefault(part, {})
            if not isinstance(node, (dict, list)):
                raise SceneError(".".join(parts[: i + 1]), "is a value, not a section")


Overrides = typing.Iterable[str] | typing.Mapping[str, Any]
"""``"key=value"`` strings (as ``--set`` takes them) or a mapping ``{"damping.gamma_per_s": 0.5}``."""


def override_pairs(overrides: Overrides) -> list[tuple[str, Any]]:
    """``(key, value)`` of each override: strings parsed as ``--set`` parses them, a
    mapping's values taken as they are (Python numbers, strings, booleans, lists)."""
    if isinstance(overrides, str):
        raise ArgumentTypeError(
            "overrides", f"must be a list of 'key=value' strings or a dict, not one string {overrides!r}"
        )
    if isinstance(overrides, typing.Mapping):
        return [(str(key), value) for key, value in overrides.items()]
    pairs = []
    for i, item in enumerate(overrides):
        if not isinstance(item, str):
            raise ArgumentTypeError(
                "overrides",
                f"an override must be a 'key=value' string, got {item!r} (item {i}); pass a dict for Python values",
            )
        if "=" not in item:
            raise SceneError(item, "an override must look like section.field=value")
        key, text = item.split("=", 1)
        pairs.append((key.strip(), _parse_value(text.strip())))
    return pairs


def apply_overrides(data: dict, overrides: Overrides) -> dict:
    """Return a copy of raw scene ``data`` with overrides applied (:data:`Overrides`).

    Keys are dotted field names (``integrator.dt_s``); list items are addressed by
    index (``clamp.segments.1.t_end_s``). String values are TOML literals; a bare word is
    a string. Unknown keys are reported when the result is parsed. A
    ``material.from_file`` override replaces the scene's own material values by the
    file's; the other ``material.*`` overrides apply on top of it, wherever they stand.
    """
    data = copy.deepcopy(data)
    # stable sort: the material file first, so that it cannot undo a field override
    for key, value in sorted(override_pairs(overrides), key=lambda pair: not is_material_file_key(pair[0])):
        set_field(data, key, value)
    return data
