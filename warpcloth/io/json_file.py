"""Reading the JSON files warpcloth writes (meta.json, sweep.json) back, or saying why not."""

from __future__ import annotations

import json
from pathlib import Path

from warpcloth.errors import DataFileError


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
