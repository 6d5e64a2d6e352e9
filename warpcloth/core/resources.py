"""What a run will take, estimated before it is taken: memory for the recorded results
and disk for the streamed files. Work that does not fit is refused with its numbers and
the fields or options that shrink it, instead of failing (or swapping) part way."""

from __future__ import annotations

import os
import shutil
from decimal import Decimal
from pathlib import Path

from warpcloth.errors import ResourceError

MEMORY_FRACTION = 0.5
"""Share of the memory available now that one run's recorded results may take."""


def available_memory() -> int:
    """Bytes of memory available to a new allocation (Linux MemAvailable, else free pages)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


def size_text(n: float) -> str:
    """A byte count for a message: three digits and a decimal unit (any Python integer,
    however far beyond a float's range, is written without overflowing)."""
    n = Decimal(n)
    unit, scale = next(
        ((u, s) for u, s in (("TB", 12), ("GB", 9), ("MB", 6), ("kB", 3)) if n >= Decimal(10) ** s), ("B", 0)
    )
    value = n.scaleb(-scale)
    return f"{float(value):.3g} {unit}" if value < Decimal("1e300") else f"{value:.3g} {unit}"


def duration_text(seconds: float) -> str:
    """A duration as a person reads it: seconds, minutes, hours or days, 3 digits."""
    for unit, size in (("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def check_memory(needed: int, what: str, knobs: str, available: int | None = None) -> None:
    """Refuse ``needed`` bytes of ``what`` when over :data:`MEMORY_FRACTION` of the memory available."""
    available = available_memory() if available is None else available
    if needed > MEMORY_FRACTION * available:
        raise ResourceError(
            f"{what} would take {size_text(needed)} of memory, more than "
            f"{MEMORY_FRACTION:.0%} of the {size_text(available)} available; {knobs}"
        )


def check_disk(target: str | Path, needed: int, what: str, knobs: str) -> None:
    """Refuse writing ``needed`` bytes of ``what`` to ``target`` (a path that may not exist
    yet) when its file system has less free."""
    target = Path(target)
    existing = next(p for p in (target, *target.absolute().parents) if p.exists())
    free = shutil.disk_usage(existing).free
    if needed > free:
        raise ResourceError(
            f"{what} would write {size_text(needed)} to {target}, whose file system has {size_text(free)} free; {knobs}"
        )
