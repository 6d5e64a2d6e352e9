"""Generate the bundled KES example data: ``kes_fb1_example.csv``, ``kes_fb2_example.csv``,
``kes_fb2_inner_loops.csv`` and ``kes_fb1_shear_example.csv``.

They are synthetic: the model itself with known parameters plus seeded Gaussian noise,
so that ``warpcloth material fit-kes`` can be checked against the truth. The material is
The illustrative wool 90 % / nylon 10 % (``warpcloth.scene.DEFAULT_MATERIAL``):
tensile a = (2000, 0, 0, 2.93e7) gf/cm, D = 0.10 gf·cm²/cm, D1 = 0.04 gf·cm/cm,
α = 5 cm, K0 = 2.5 1/cm.

``kes_fb1_example.csv`` (header ``strain_percent,force_gf_per_cm``): loading from 0 to
the strain εm where T(εm) = 500 gf/cm (the KES-FB1 standard maximum load; εm = 6.001 %),
121 points equally spaced in strain, force T(ε) of the quartic; then unloading back to 0
at the same strains (120 more points). The model has no tensile hysteresis, so the
unloading force follows a stated simple rule: the loading curve scaled by (ε/εm)³,
i.e. T(ε)·(ε/εm)³, which starts at Fm and ends at 0 below the loading curve (without
noise: EMT 6.001 %, WT 8.162 gf·cm/cm², LT 0.544, RT 52.6 %). Noise: Gaussian,
σ = 2 gf/cm, on every force (seed 2026); strain noise-free.

``kes_fb2_example.csv`` (header ``curvature_per_cm,moment_gf_cm_per_cm``): the standard
KES-FB2 cycle 0 → +2.5 → −2.5 → 0 1/cm in steps of 0.02 1/cm (501 points); the moment is
the strip kernel's own hinge law along that path (``warpcloth.strip.moment_along_path``,
the hinge starting fresh at K = 0; without noise B = 0.1004 gf·cm²/cm, 2HB = 0.0399
gf·cm/cm), plus Gaussian noise σ = 0.002 gf·cm/cm (seed 2027); curvature noise-free (the
instruments' controlled variable).

``kes_fb2_inner_loops.csv`` (same header): the standard cycle, then partial cycles inside
it, 0 → +2.5 → −2.5, then three times +2.0 ↔ +1.6, then −0.8 ↔ −0.4 twice, and back to
0 1/cm, in steps of 0.02 1/cm. Its
moment is not warpcloth's: an Iwan model (4096 Jenkins elements in parallel, the textbook
model of fibre friction, written out here in NumPy) whose virgin curve is the default
material's ½ D1 (1 − e^{−2α|K|}), plus D K, plus the same noise (seed 2028). A record
that shows which law's inner loops a fabric has: `warpcloth material compare --bending
kes_fb2_inner_loops`.

``kes_fb1_shear_example.csv`` (header ``shear_angle_deg,shear_force_gf_per_cm``): the
standard KES-FB1 shear cycle 0 → +8 → −8 → 0° in steps of 0.05° (641 points). Its force is
not warpcloth's either: Fs = G φ + the same Iwan model on the angle (a fabric's yarn
crossings as Jenkins elements), with G = 0.6 gf/(cm·°), D1 = 0.8 gf/cm, α = 0.6 /°
(illustrative values of a wool suiting's order; its loop narrows away from φ = 0, as the
laws' do), plus Gaussian noise σ = 0.01 gf/cm (seed 2029); the angle noise-free.

Run ``python scenes/data/make_kes_examples.py`` to rewrite the files next to this script.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from warpcloth import units
from warpcloth.calibrate.kes import PERCENT, standard_cycle
from warpcloth.scene import DEFAULT_MATERIAL, MaterialSection, to_si
from warpcloth.strip import moment_along_path

HERE = Path(__file__).resolve().parent
MAX_LOAD_GF_PER_CM = 500.0
TENSILE_POINTS = 121
TENSILE_NOISE_GF_PER_CM = 2.0
UNLOADING_EXPONENT = 3
CURVATURE_STEP_PER_CM = 0.02
BENDING_NOISE_GF_CM_PER_CM = 0.002
SHEAR_TRUTH = {"rigidity_gf_per_cm_deg": 0.6, "hysteresis_d1_gf_per_cm": 0.8, "hysteresis_alpha_per_deg": 0.6}
SHEAR_PHI0_DEG = 8.0
SHEAR_STEP_DEG = 0.05
SHEAR_NOISE_GF_PER_CM = 0.01


def tensile_example() -> np.ndarray:
    """Rows (strain in %, force per width in gf/cm): loading to 500 gf/cm, then unloading."""
    a = DEFAULT_MATERIAL["tensile_gf_per_cm"]
    quartic = np.polynomial.Polynomial([0.0, *a])
    roots = (quartic - MAX_LOAD_GF_PER_CM).roots()
    em = min(r.real for r in roots if abs(r.imag) < 1e-9 and r.real > 0)
    loading = np.linspace(0.0, em, TENSILE_POINTS)
    unloading = loading[::-1][1:]
    strain = np.concatenate([loading, unloading])
    force = np.concatenate([quartic(loading), quartic(unloading) * (unloading / em) ** UNLOADING_EXPONENT])
    force += np.random.default_rng(2026).normal(0.0, TENSILE_NOISE_GF_PER_CM, len(force))
    return np.column_stack([strain / PERCENT, force])


def bending_example() -> np.ndarray:
    """Rows (curvature in 1/cm, moment per width in gf·cm/cm) of the cycle 0 → +2.5 → −2.5 → 0."""
    k = standard_cycle(DEFAULT_MATERIAL["hysteresis_k0_per_cm"], CURVATURE_STEP_PER_CM)
    moment, _ = moment_along_path(to_si(MaterialSection()), k * units.CURVATURE_PER_CM)
    moment = moment / units.MOMENT_GF_CM_PER_CM
    moment += np.random.default_rng(2027).normal(0.0, BENDING_NOISE_GF_CM_PER_CM, len(moment))
    return np.column_stack([k, moment])


INNER_KNOTS_PER_CM = (0.0, 2.5, -2.5, 2.0, 1.6, 2.0, 1.6, 2.0, 1.6, -0.8, -0.4, -0.8, -0.4, -0.8, 0.0)
IWAN_ELEMENTS = 4096


def iwan_moment(
    curvature_per_cm: np.ndarray, d1: float, alpha_cm: float, elements: int = IWAN_ELEMENTS, growth_cm: float = 0.0
) -> np.ndarray:
    """Hysteretic moment (units of ``d1``) of an Iwan model along a curvature path from rest:
    Jenkins elements of stiffness α D1 / N whose sliders slip at curvatures κ_i, the midpoint
    quantiles of the density 2α e^{−2ακ} (virgin curve ½ D1 (1 − e^{−2α|K|}) as N → ∞).
    With ``growth_cm`` β every slider's friction grows by √(1 + (β (K − K_start))²) with
    the distance from the path's first curvature (the masing_growing law's continuum limit)."""
    q = (np.arange(elements) + 0.5) / elements
    stiffness = alpha_cm * d1 / elements
    slip = stiffness * -np.log1p(-q) / (2 * alpha_cm)
    force = np.zeros(elements)
    out = [0.0]
    start = curvature_per_cm[0]
    for a, b in zip(curvature_per_cm[:-1], curvature_per_cm[1:], strict=True):
        limit = slip * np.sqrt(1.0 + (growth_cm * (b - start)) ** 2)
        force = np.clip(force + stiffness * (b - a), -limit, limit)
        out.append(force.sum())
    return np.array(out)


def inner_loops_example() -> np.ndarray:
    """Rows (curvature in 1/cm, moment per width in gf·cm/cm) of the cycle with partial cycles."""
    legs = [
        np.linspace(a, b, max(round(abs(b - a) / CURVATURE_STEP_PER_CM), 1), endpoint=False)
        for a, b in zip(INNER_KNOTS_PER_CM[:-1], INNER_KNOTS_PER_CM[1:], strict=True)
    ]
    k = np.concatenate([*legs, [INNER_KNOTS_PER_CM[-1]]])
    moment = DEFAULT_MATERIAL["bending_rigidity_gf_cm2_per_cm"] * k + iwan_moment(
        k, DEFAULT_MATERIAL["hysteresis_d1_gf_cm_per_cm"], DEFAULT_MATERIAL["hysteresis_alpha_cm"]
    )
    moment += np.random.default_rng(2028).normal(0.0, BENDING_NOISE_GF_CM_PER_CM, len(moment))
    return np.column_stack([k, moment])


def shear_example() -> np.ndarray:
    """Rows (shear angle in degrees, shear force per width in gf/cm) of the cycle 0 → +8 → −8 → 0°."""
    phi = standard_cycle(SHEAR_PHI0_DEG, SHEAR_STEP_DEG)
    force = SHEAR_TRUTH["rigidity_gf_per_cm_deg"] * phi + iwan_moment(
        phi, SHEAR_TRUTH["hysteresis_d1_gf_per_cm"], SHEAR_TRUTH["hysteresis_alpha_per_deg"]
    )
    force += np.random.default_rng(2029).normal(0.0, SHEAR_NOISE_GF_PER_CM, len(force))
    return np.column_stack([phi, force])


EXAMPLES = {
    "kes_fb1_example.csv": (tensile_example, ("%.4f", "%.3f"), "strain_percent,force_gf_per_cm"),
    "kes_fb2_example.csv": (bending_example, ("%.3f", "%.5f"), "curvature_per_cm,moment_gf_cm_per_cm"),
    "kes_fb2_inner_loops.csv": (inner_loops_example, ("%.3f", "%.5f"), "curvature_per_cm,moment_gf_cm_per_cm"),
    "kes_fb1_shear_example.csv": (shear_example, ("%.2f", "%.4f"), "shear_angle_deg,shear_force_gf_per_cm"),
}
"""Each file: the function that makes its rows, the columns' formats, its header."""


def main() -> None:
    """Write the example files next to this script."""
    for name, (rows, fmt, header) in EXAMPLES.items():
        np.savetxt(HERE / name, rows(), fmt=fmt, delimiter=",", header=header, comments="")


if __name__ == "__main__":
    main()
