"""Raw TOML → schema dataclasses: type coercion and range checks, field by field.

Every error names the dotted field and the offending value.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import typing
from pathlib import Path
from typing import Any

from warpcloth.errors import DataFileError, InternalError, SceneError

from .schema import field_types


def coerce_value(value: Any, tp: Any, name: str, meta: dict) -> Any:
    """``value`` as the field type ``tp`` of field ``name``, range-checked by its metadata ``meta``."""
    origin = typing.get_origin(tp)
    if origin is list:
        (item,) = typing.get_args(tp)
        if not isinstance(value, list):
            raise SceneError(name, f"expected a list, got {value!r}")
        if dataclasses.is_dataclass(item):
            return [parse_section(item, v, f"{name}[{i}]") for i, v in enumerate(value)]
        return [coerce_value(v, item, f"{name}[{i}]", {}) for i, v in enumerate(value)]
    if tp is bool:
        if not isinstance(value, bool):
            raise SceneError(name, f"expected true or false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(name, f"expected an integer, got {value!r}")
        out: Any = value
    elif tp is float:
        words = meta.get("words") or ()
        if isinstance(value, str) and value in words:
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            also = "".join(f" or {w!r}" for w in words)
            raise SceneError(name, f"expected a number{also}, got {value!r}")
        out = float(value)
        if not math.isfinite(out):
            raise SceneError(name, f"must be a finite number, got {out}")
    elif tp is str:
        if not isinstance(value, str):
            raise SceneError(name, f"expected a string, got {value!r}")
        choices = meta.get("choices")
        if choices and value not in choices:
            raise SceneError(name, f"must be one of {', '.join(choices)}; got {value!r}")
        return value
    else:  # pragma: no cover - schema error, not user error
        raise InternalError(
            f"the scene schema gives {name} the type {tp}, which the parser does not read: "
            "a bug in warpcloth, please report it"
        )
    if meta.get("gt") is not None and not out > meta["gt"]:
        raise SceneError(name, f"must be > {meta['gt']:g}, got {out:g}")
    if meta.get("ge") is not None and not out >= meta["ge"]:
        raise SceneError(name, f"must be ≥ {meta['ge']:g}, got {out:g}")
    return out


def parse_section(cls: type, data: Any, prefix: str) -> Any:
    """Parse the raw table ``data`` into the dataclass ``cls``; ``prefix`` is its dotted name."""
    if not isinstance(data, dict):
        raise SceneError(prefix or "scene", f"expected a table, got {data!r}")
    hints = field_types(cls)
    known = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in known:
            where = f"{prefix}.{key}" if prefix else key
            raise SceneError(where, f"unknown field; known fields here: {', '.join(known)}")
    kwargs = {}
    for name, f in known.items():
        if name not in data:
            continue
        where = f"{prefix}.{name}" if prefix else name
        tp = hints[name]
        if dataclasses.is_dataclass(tp):
            kwargs[name] = parse_section(tp, data[name], where)
        else:
            kwargs[name] = coerce_value(data[name], tp, where, dict(f.metadata))
    return cls(**kwargs)


def read_toml_text(path: Path) -> str:
    """The text of a TOML file (UTF-8, as TOML requires; a byte-order mark is dropped);
    a file that is not UTF-8 text is a DataFileError naming it, not a traceback."""
    try:
        return path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataFileError(
            path,
            f"is not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset {exc.start}); "
            "a scene or material file is TOML, which is UTF-8",
        ) from None


def parse_toml(text: str, where: str, field: str) -> dict:
    """TOML ``text`` read from ``where``; a syntax error is a SceneError of ``field``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(field, f"{where} is not valid TOML: {exc}") from None
