"""Errors that warpcloth raises with a message meant for the person who wrote the input."""

from __future__ import annotations


class SceneError(ValueError):
    """A scene or material field is missing, unknown, mistyped or out of range.

    ``field`` is the dotted name of the offending field (e.g. ``strip.spacing_mm``).
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        super().__init__(f"{field}: {message}")


class DivergenceError(RuntimeError):
    """A strip's state became non-finite or physically absurd during a run.

    ``diverged`` lists one dict per diverged strip (strip, time, step, quantity, where,
    value); ``result`` holds everything recorded before the divergence.
    """

    def __init__(self, message: str, diverged: list[dict], result: object = None) -> None:
        self.diverged = diverged
        self.result = result
        super().__init__(message)
