"""KES ↔ SI conversion: the one place where Kawabata units meet SI.

Everything inside warpcloth is SI (m, kg, s, N). Materials are entered in the units
of the Kawabata Evaluation System (KES-FB) instruments and converted here, once.
"""

from __future__ import annotations

GF_TO_N = 9.80665e-3
"""One gram-force in newtons."""

TENSILE_GF_PER_CM = GF_TO_N / 1e-2
"""Tensile force per width: gf/cm → N/m (× 0.980665)."""

MOMENT_GF_CM_PER_CM = GF_TO_N
"""Bending moment per width (M, 2HB, D1): gf·cm/cm → N·m/m = N (× 9.80665e-3)."""

RIGIDITY_GF_CM2_PER_CM = GF_TO_N * 1e-2
"""Bending rigidity per width (B, D): gf·cm²/cm → N·m²/m = N·m (× 9.80665e-5)."""

CURVATURE_PER_CM = 100.0
"""Curvature: 1/cm → 1/m."""

LENGTH_CM = 1e-2
"""Length (hysteresis steepness α): cm → m."""

AREAL_DENSITY_G_PER_CM2 = 10.0
"""Mass per area: g/cm² → kg/m²."""

LENGTH_MM = 1e-3
"""Scene lengths: mm → m."""

STRAIN_PERCENT = 1e-2
"""Strain written in % (KES-FB1 EMT, tensile CSVs) → fraction."""


MEASURED_UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6},
    "length": {"m": 1.0, "cm": 1e-2, "mm": LENGTH_MM, "um": 1e-6, "µm": 1e-6},
    "angle": {"rad": 1.0, "mrad": 1e-3, "deg": 0.017453292519943295},
}
"""Units a measured-data header may name per quantity (``t_ms``, ``x_m``, ``theta [deg]``),
and each one's factor to SI (s, m, rad)."""
