"""The force terms a model is built with, checked before any kernel is generated
(the terms themselves: kernels/force_terms.py)."""

from __future__ import annotations

from typing import Any

from warpcloth.errors import ArgumentError
from warpcloth.kernels.force_terms import FORCE_TERMS


def checked_terms(terms: object) -> tuple[Any, ...]:
    """``terms`` as a tuple of force terms (each with ``channel`` and ``build``, channels
    unique), or an ArgumentError naming the first that is not one."""
    try:
        items = tuple(terms)  # type: ignore[arg-type]
    except TypeError:
        raise ArgumentError("terms", f"must be a sequence of force terms, got {terms!r}") from None
    channels = []
    for i, term in enumerate(items):
        if not (hasattr(term, "channel") and callable(getattr(term, "build", None))):
            raise ArgumentError("terms", f"[{i}] is {term!r}, not a force term ({', '.join(FORCE_TERMS)})")
        channels.append(term.channel)
    if len(set(channels)) != len(channels):
        raise ArgumentError("terms", f"two terms tally their work in one channel: {channels}")
    return items
