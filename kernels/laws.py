"""The bending laws a strip can use, by name (``StripBuilder.finalize(bending_law=...)``).

Adding a law: a new ``bending_<name>.py`` with the same interface as
:mod:`.bending_tagawa2003` (NAME, PARAMETERS, MEMORY, ``packed_parameters``, ``build``)
and one entry here.
"""

from types import ModuleType

from . import bending_tagawa2003

BENDING_LAWS: dict[str, ModuleType] = {bending_tagawa2003.NAME: bending_tagawa2003}
DEFAULT_BENDING_LAW = bending_tagawa2003.NAME


def bending_law(name: str) -> ModuleType:
    """The module of the bending law ``name``; KeyError lists the known ones."""
    try:
        return BENDING_LAWS[name]
    except KeyError:
        raise KeyError(f"unknown bending law {name!r}; known: {', '.join(BENDING_LAWS)}") from None
