"""The JSON files warpcloth writes (meta.json, sweep.json, fit.json, a tracking record):
strict JSON on the way out, read back or refused on the way in."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from warpcloth.errors import DataFileError


def _finite_or_null(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_null(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item") and hasattr(value, "dtype"):  # a NumPy scalar
        return _finite_or_null(value.item())
    return value


def json_text(value: Any, indent: int = 1) -> str:
    """``value`` as strict JSON: a number that has no value (NaN, ±inf: a σ from too few
    resamples, an energy that diverged) is ``null``, never the ``NaN`` that other JSON
    readers refuse; anything that is not JSON is an error here, not a file half written."""
    return json.dumps(_finite_or_null(value), indent=indent, allow_nan=False, default=str)


def read_json(path: Path) -> dict:
    """The JSON object in ``path``; a missing, unreadable or damaged file is a DataFileError."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFileError(path, "is missing; the directory is damaged or was not written by warpcloth") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataFileError(path, f"is damaged (not valid JSON: {exc})") from None
    if not isinstance(data, dict):
        raise DataFileError(path, "is damaged (not a JSON object)")
    return data
