"""What every figure shares: the headless backend, the file writer (:func:`save`), the
resolution and formats, axis names and units, and the colours and labels of variants.

Axes are in the units a textile lab reads: mm, degrees, and KES units for the bending
loop (curvature in 1/cm, moment per width in gf·cm/cm), converted via ``units``.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed, on CI or a cluster node

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from warpcloth import units  # noqa: E402
from warpcloth.io.atomic import write_atomically  # noqa: E402
from warpcloth.io.recording import Recording  # noqa: E402
from warpcloth.kernels.law import BENDING_RIGIDITY  # noqa: E402
from warpcloth.kernels.laws import LAW_PARAMETERS  # noqa: E402
from warpcloth.viz import DPI, FORMATS  # noqa: E402
from warpcloth.viz.geometry import colour_values  # noqa: E402

__all__ = [
    "DPI",
    "FIELD_LABELS",
    "FORMATS",
    "LEGEND_VARIANTS",
    "MM",
    "X_LABEL",
    "Y_LABEL",
    "colours_and_labels",
    "plt",
    "field_label",
    "field_unit",
    "inside",
    "legend",
    "save",
    "time_label",
    "variant_label",
    "window_note",
]

MM = 1 / units.LENGTH_MM

X_LABEL = "x from the clamp edge (mm)"
Y_LABEL = "y from the clamp edge (mm)"
"""The axes of every figure of the strip's shape (positions from the clamp edge at rest)."""


def time_label(recording: Recording, unit: bool = True) -> str:
    """The time axis' name: "t after release" when every scene releases its strip at
    t = 0, else plain "t" (a driven clamp, as in the impulsive rotation, has no release:
    its t = 0 is the start of the motion); ``unit`` adds " (s)"."""
    name = "t after release" if all(s.release.enabled for s in recording.scenes) else "t"
    return f"{name} (s)" if unit else name


def variant_label(recording: Recording, j: int) -> str:
    """Variant ``j``'s name in a legend: its number and the first two parameters that vary."""
    varying = recording.varying[:2]
    values = [recording.parameters[c].iloc[j] for c in varying]
    parts = [
        f"{c.split('.')[-1]}={v:.3g}" if isinstance(v, float) else f"{c.split('.')[-1]}={v}"
        for c, v in zip(varying, values, strict=True)
    ]
    return f"variant {recording.variants[j]}" + (f" ({', '.join(parts)})" if parts else "")


LEGEND_VARIANTS = 8
"""Up to this many variants get a legend entry each; more are coloured by a parameter."""


def colours_and_labels(recording: Recording, fig: plt.Figure, ax: plt.Axes) -> list[tuple[object, str | None]]:
    """A colour and a legend label per variant: its own entry for a few variants; for
    many, viridis keyed to the first parameter that varies, with a colourbar, and no
    legend entries (a 100-entry legend would cover the axes)."""
    n = len(recording.variants)
    if n <= LEGEND_VARIANTS:
        return [(f"C{j}", variant_label(recording, j)) for j in range(n)]
    key = recording.varying[0] if recording.varying else "variant"
    values = colour_values(recording)  # as renders and USD colour them (a choice by its values' order)
    norm = matplotlib.colors.Normalize(values.min(), values.max() if values.max() > values.min() else None)
    fig.colorbar(matplotlib.cm.ScalarMappable(norm, "viridis"), ax=ax, label=field_label(key))
    return [(plt.cm.viridis(norm(v)), None) for v in values]


def legend(ax: plt.Axes, **style: object) -> None:
    """A legend, unless nothing is labelled (many variants are labelled by a colourbar)."""
    if ax.get_legend_handles_labels()[0]:  # many variants are labelled by a colourbar instead
        ax.legend(**style)


FIELD_LABELS = {
    "damping.gamma_per_s": ("γ", "s⁻¹"),
    # every bending law's parameters, D's included, as their descriptions label them
    **{
        f"material.{p.scene_field}": (p.label, units.BENDING_UNITS[p.kind][1])
        for p in (BENDING_RIGIDITY, *(parameter for parameter, _ in LAW_PARAMETERS.values()))
    },
    "material.density_g_per_cm2": ("ρ_A", "g/cm²"),
    "material.bending_law": ("bending law", ""),
    "clamp.rotation_centre_dx_mm": ("rotation centre dx", "mm"),
    "clamp.rotation_centre_dy_mm": ("rotation centre dy", "mm"),
    "release.hold_x_mm": ("hold x", "mm"),
    "release.hold_y_mm": ("hold y", "mm"),
    "time_shift_s": ("clock offset δ", "s"),
    "shear.rigidity_gf_per_cm_deg": ("G", "gf/(cm·°)"),
    "peak_shear_angle_deg": ("probed cell's peak shear angle", "°"),
    "energy_drift_relative": ("energy budget's drift per the clamp's work", ""),
    "drive_work_J": ("work of the clamp", "J"),
    "first_period_s": ("first period", "s"),
    "first_amplitude_m": ("first amplitude", "m"),
    "mean_log_decrement": ("mean log decrement per half-cycle", ""),
    "n_half_cycles": ("half-cycles", ""),
    "peak_tip_speed_m_per_s": ("peak tip speed", "m/s"),
    "hysteresis_work_J": ("hysteresis work", "J"),
    "damping_work_J": ("damping work", "J"),
}
"""Symbols and units for the fields figures name; anything else shows its own name."""


MARKER_METRICS = {
    "peak_displacement_mm": "peak displacement",
    "peak_z_mm": "peak sideways z",
    "peak_x_mm": "peak out-of-plane x",
    "peak_z_against_clamp_mm": "peak sideways z against the clamp",
}
"""A sheet sweep's per-marker summary columns, ``marker_<k>_<metric>`` (mm)."""


def _symbol_and_unit(name: str) -> tuple[str, str]:
    # a known field's, a sheet marker's metric's (marker_<k>_<metric>), else the name itself
    if name in FIELD_LABELS:
        return FIELD_LABELS[name]
    marker, _, metric = name.removeprefix("marker_").partition("_")
    if name.startswith("marker_") and marker.isdigit() and metric in MARKER_METRICS:
        return f"marker {marker}'s {MARKER_METRICS[metric]}", "mm"
    return name, ""


def field_unit(name: str) -> str:
    """The unit a figure writes for ``name`` ("" if none is known)."""
    return _symbol_and_unit(name)[1]


def field_label(name: str, units: bool = True) -> str:
    """An axis label: the field's symbol and unit (``γ (s⁻¹)``), else its dotted name."""
    symbol, unit = _symbol_and_unit(name)
    return f"{symbol} ({unit})" if units and unit else symbol


def save(fig: plt.Figure, path: Path, dpi: float = DPI) -> Path:
    """Write ``fig`` to ``path`` whole or not at all (its suffix chooses the format), and
    close it."""
    fig.tight_layout()
    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png"))
    plt.close(fig)
    return path


def inside(t: np.ndarray, window: tuple[float, float] | None) -> np.ndarray:
    """Which samples lie within a comparison window (all of them without one)."""
    if window is None:
        return np.ones(len(t), bool)
    return (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)


def window_note(window: tuple[float, float] | None) -> str:
    """What a title adds for a comparison window ("" without one), on a line of its own so
    the title stays within the figure's width."""
    return "" if window is None else f"\ncompared on t = {window[0]:g} … {window[1]:g} s"
