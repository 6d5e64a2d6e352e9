"""Warp kernels of warpcloth, installed as ``warpcloth.kernels``.

The physics lives here; :mod:`warpcloth` only builds arrays and launches.
"""

from .strip import (
    FORWARD,
    PROBE_FIELDS,
    PROBE_INDEX,
    SEMI_IMPLICIT,
    STATUS_FOLDED,
    STATUS_NONFINITE_ENERGY,
    STATUS_OK,
    STATUS_STRAIN,
    KernelSet,
    build_kernels,
)

__all__ = [
    "FORWARD",
    "PROBE_FIELDS",
    "PROBE_INDEX",
    "SEMI_IMPLICIT",
    "STATUS_FOLDED",
    "STATUS_NONFINITE_ENERGY",
    "STATUS_OK",
    "STATUS_STRAIN",
    "KernelSet",
    "build_kernels",
]
