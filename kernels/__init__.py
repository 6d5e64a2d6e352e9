"""Warp kernels of warpcloth, installed as ``warpcloth.kernels`` (docs/model.md).

One file per concern, each building its Warp functions per precision (``build``):

- :mod:`.types` — vectors and matrices of a precision
- :mod:`.tensile` — tensile law T(ε), its energy and tangent
- :mod:`.bending_tagawa2003`, :mod:`.bending_dahl`, :mod:`.bending_frictional_couple` — the bending laws
  (the paper's, Dahl's, Grosberg's frictional couple); :mod:`.laws` lists them and dispatches per strip
- :mod:`.geometry` — normals and hinge curvature of a chain
- :mod:`.drives` — clamp rotation θ(t) and the held free end
- :mod:`.integrators` — explicit Euler node updates and the stepping struct
- :mod:`.structs` — what a strip is (``StripModel``) and is doing (``StripState``)
- :mod:`.forces` — the internal-force pass
- :mod:`.probes` — the recorded quantities
- :mod:`.strip` — the fused kernel that advances a batch through many substeps

Only Warp and the standard library are imported here; :mod:`warpcloth` builds arrays
and launches.
"""

from . import bending_dahl, bending_frictional_couple, bending_tagawa2003, drives, laws, structs
from .drives import MAX_DEGREE
from .laws import BENDING_LAWS, DEFAULT_BENDING_LAW, bending_law, packed_parameters
from .probes import PROBE_FIELDS, PROBE_INDEX, PROBE_UNITS
from .status import STATUS_BUDGET, STATUS_FOLDED, STATUS_NONFINITE_ENERGY, STATUS_OK, STATUS_STRAIN
from .strip import build as build_strip
from .strip import hinge_kernels
from .types import Precision, precision

__all__ = [
    "BENDING_LAWS",
    "DEFAULT_BENDING_LAW",
    "MAX_DEGREE",
    "Precision",
    "PROBE_FIELDS",
    "PROBE_INDEX",
    "PROBE_UNITS",
    "STATUS_BUDGET",
    "STATUS_FOLDED",
    "STATUS_NONFINITE_ENERGY",
    "STATUS_OK",
    "STATUS_STRAIN",
    "bending_dahl",
    "bending_frictional_couple",
    "bending_law",
    "bending_tagawa2003",
    "build_strip",
    "drives",
    "hinge_kernels",
    "laws",
    "packed_parameters",
    "precision",
    "structs",
]
