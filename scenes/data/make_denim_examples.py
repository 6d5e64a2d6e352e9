"""Generate KES-FB1 shear and KES-FB2 bending records of four named denims from their
published KES values: ``denim_<fabric>_fb1_shear.csv``, ``denim_<fabric>_fb2.csv``,
``denim_<fabric>_fb1.csv`` (tensile) and ``denims.json``.

**What is the paper's.** A. Kumari and K. Khurana, "Regenerated Cellulose-Based Denim
Fabric for Tropical Regions: An Analytical Study on Making Denim Comfortable", Journal of
Textiles 2016, Article ID 4614168 (Hindawi, CC BY), Table 5 ("Primary hand values",
KES-FB), fabrics A, C, D and F: B (gf·cm²/cm), 2HB (gf·cm/cm), G (gf/(cm·°)), 2HG and 2HG5
(gf/cm), EMT (%), LT and RT (%), thickness T (mm) and weight W as the table prints it (its unit column says mg/cm²,
which for 94–109 would be 0.94–1.09 kg/m², three times a denim's; ``denims.json`` keeps the
number as printed and says so). Only these summary values are published: no loop.

**What is ours.** A loop consistent with them, made by a model that is not warpcloth's
kernels: an Iwan model (4096 Jenkins elements in parallel, NumPy,
:func:`make_kes_examples.iwan_moment`) on the standard KES cycles (shear 0 → +8 → −8 → 0° in
steps of 0.05°, bending 0 → +2.5 → −2.5 → 0 1/cm in steps of 0.02 1/cm), plus a linear
elastic part. In shear every slider's friction grows with the angle by √(1 + (β φ)²) (the
yarns pressed together toward jamming; without it no Iwan loop widens toward φ0), in
bending it does not. The branch steepness is ours (α = 2 /° in shear, 5 cm in bending);
the other three parameters of each loop (the elastic slope, D1, β; the elastic slope and
D1 in bending) are solved so that the noise-free record's own KES values, read by
warpcloth's KES reader (:func:`warpcloth.calibrate.kes.shear_summary`, the standard
definitions), are the published ones to 1e-6. Then seeded Gaussian noise on the force:
σ = 0.02 gf/cm in shear, 0.002 gf·cm/cm in bending (the bundled examples' order); the
angle and curvature noise-free (the instruments' controlled variable).

The tensile record is T(ε) = a1 ε + a3 ε³ to Fm = 500 gf/cm, the one such curve with the
published EMT and LT, and back by T(ε)(ε/εm)^n with n for the published RT (the bundled
example's unloading rule), noise σ = 2 gf/cm; the cubic is ours.

So a fit that reproduces G, 2HG and 2HG5 shows that a law *can* make such a loop; the
loop's shape between those values is this script's assumption, not a measurement.

Run ``python scenes/data/make_denim_examples.py`` to rewrite the files next to this script.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
from make_kes_examples import IWAN_ELEMENTS, iwan_moment
from make_motion_examples import sheet_marker_rows, sheet_paths
from scipy.optimize import least_squares

from warpcloth.calibrate.kes import bending_loop, bending_summary, shear_loop, shear_summary, standard_cycle

HERE = Path(__file__).resolve().parent
SOURCE = (
    'A. Kumari and K. Khurana, "Regenerated Cellulose-Based Denim Fabric for Tropical Regions: An Analytical '
    'Study on Making Denim Comfortable", Journal of Textiles 2016, 4614168, Table 5 (KES-FB primary hand values)'
)
PUBLISHED = {
    # fabric: B gf·cm²/cm, 2HB gf·cm/cm, G gf/(cm·°), 2HG gf/cm, 2HG5 gf/cm, thickness mm, weight as printed
    # EMT %, LT, RT %: KES-FB1 tensile to Fm = 500 gf/cm
    "A": {
        "B": 0.172,
        "2HB": 0.139,
        "G": 2.180,
        "2HG": 5.012,
        "2HG5": 7.412,
        "T_mm": 1.066,
        "W_printed": 104.0,
        "EMT": 5.515,
        "LT": 0.712,
        "RT": 54.100,
    },
    "C": {
        "B": 0.227,
        "2HB": 0.105,
        "G": 3.398,
        "2HG": 4.975,
        "2HG5": 7.400,
        "T_mm": 0.801,
        "W_printed": 93.89,
        "EMT": 4.695,
        "LT": 0.780,
        "RT": 65.975,
    },
    "D": {
        "B": 0.147,
        "2HB": 0.141,
        "G": 1.613,
        "2HG": 3.513,
        "2HG5": 6.412,
        "T_mm": 1.040,
        "W_printed": 107.77,
        "EMT": 5.135,
        "LT": 0.676,
        "RT": 52.450,
    },
    "F": {
        "B": 0.148,
        "2HB": 0.159,
        "G": 1.500,
        "2HG": 3.425,
        "2HG5": 5.763,
        "T_mm": 0.973,
        "W_printed": 104.89,
        "EMT": 5.455,
        "LT": 0.657,
        "RT": 55.890,
    },
}
SHEAR_PHI0_DEG = 8.0
SHEAR_STEP_DEG = 0.05
SHEAR_ALPHA_PER_DEG = 2.0
SHEAR_NOISE_GF_PER_CM = 0.02
BENDING_K0_PER_CM = 2.5
BENDING_STEP_PER_CM = 0.02
BENDING_ALPHA_CM = 5.0
BENDING_NOISE_GF_CM_PER_CM = 0.002
SEEDS = {"A": 3101, "C": 3103, "D": 3104, "F": 3106}
TENSILE_FM_GF_PER_CM = 500.0
TENSILE_POINTS = 121
TENSILE_NOISE_GF_PER_CM = 2.0


def tensile_record(published: dict, rng: np.random.Generator) -> tuple[np.ndarray, dict]:
    """Rows (strain %, force gf/cm) loading to Fm = 500 gf/cm and back, and the curve's
    coefficients: T(ε) = a1 ε + a3 ε³, the one such curve with the published EMT (T(εm) =
    Fm) and LT (∫T dε = LT Fm εm / 2): a1 = Fm (2 LT − 1)/εm, a3 = (Fm − a1 εm)/εm³;
    unloading T(ε) (ε/εm)^n, n solved for the published RT (the bundled example's rule)."""
    from scipy.optimize import brentq

    em, fm, lt = published["EMT"] / 100.0, TENSILE_FM_GF_PER_CM, published["LT"]
    a1 = fm * (2 * lt - 1) / em
    a3 = (fm - a1 * em) / em**3
    work = a1 * em**2 / 2 + a3 * em**4 / 4

    def resilience(n: float) -> float:
        return (a1 * em**2 / (n + 2) + a3 * em**4 / (n + 4)) / work - published["RT"] / 100.0

    n = brentq(resilience, 0.0, 50.0)
    loading = np.linspace(0.0, em, TENSILE_POINTS)
    unloading = loading[::-1][1:]
    strain = np.concatenate([loading, unloading])
    force = np.concatenate(
        [a1 * loading + a3 * loading**3, (a1 * unloading + a3 * unloading**3) * (unloading / em) ** n]
    )
    force += rng.normal(0.0, TENSILE_NOISE_GF_PER_CM, len(force))
    return np.column_stack([100.0 * strain, force]), {"a1_gf_per_cm": a1, "a3_gf_per_cm": a3, "unloading_exponent": n}


def shear_force(phi: np.ndarray, rigidity: float, d1: float, growth: float) -> np.ndarray:
    """The noise-free shear force (gf/cm) of the record's Iwan model along ``phi`` (degrees)."""
    return rigidity * phi + iwan_moment(phi, d1, SHEAR_ALPHA_PER_DEG, IWAN_ELEMENTS, growth)


def bending_moment(k: np.ndarray, rigidity: float, d1: float) -> np.ndarray:
    """The noise-free moment (gf·cm/cm) of the record's Iwan model along ``k`` (1/cm)."""
    return rigidity * k + iwan_moment(k, d1, BENDING_ALPHA_CM, IWAN_ELEMENTS)


def solve_shear(published: dict) -> dict:
    """(elastic slope, D1, β) whose noise-free loop has the published G, 2HG and 2HG5."""
    phi = standard_cycle(SHEAR_PHI0_DEG, SHEAR_STEP_DEG)
    target = np.array([published["G"], published["2HG"], published["2HG5"]])

    def misfit(log_params: np.ndarray) -> np.ndarray:
        rigidity, d1, growth = np.exp(log_params)
        s = shear_summary(shear_loop(phi, shear_force(phi, rigidity, d1, growth), "model"))
        return np.array([s.g_gf_per_cm_deg, s.hg2_gf_per_cm, s.hg2_5_gf_per_cm]) / target - 1.0

    start = np.log([0.5 * published["G"], published["2HG"], 0.1])
    found = least_squares(misfit, start, xtol=1e-12, ftol=1e-12)
    if np.max(np.abs(found.fun)) > 1e-6:
        raise RuntimeError(f"no Iwan loop reaches the published values: {found.fun}")
    rigidity, d1, growth = np.exp(found.x)
    return {"rigidity_gf_per_cm_deg": rigidity, "hysteresis_d1_gf_per_cm": d1, "hysteresis_growth_per_deg": growth}


def solve_bending(published: dict) -> dict:
    """(elastic slope, D1) whose noise-free loop has the published B and 2HB."""
    k = standard_cycle(BENDING_K0_PER_CM, BENDING_STEP_PER_CM)
    target = np.array([published["B"], published["2HB"]])

    def misfit(log_params: np.ndarray) -> np.ndarray:
        rigidity, d1 = np.exp(log_params)
        s = bending_summary(bending_loop(k, bending_moment(k, rigidity, d1), "model"))
        return np.array([s.b_gf_cm2_per_cm, s.hb2_gf_cm_per_cm]) / target - 1.0

    found = least_squares(misfit, np.log([published["B"], published["2HB"]]), xtol=1e-12, ftol=1e-12)
    if np.max(np.abs(found.fun)) > 1e-6:
        raise RuntimeError(f"no Iwan loop reaches the published values: {found.fun}")
    rigidity, d1 = np.exp(found.x)
    return {"bending_rigidity_gf_cm2_per_cm": rigidity, "hysteresis_d1_gf_cm_per_cm": d1}


SHEET_MARKERS_RECORD_MM = 2.5
SHEET_MARKERS_NOISE_MM = 0.02


def sheet_markers(rng: np.random.Generator) -> str:
    """Denim D's shear swing (the bundled scene with scenes/materials/denim-D.toml, 0.3 s):
    its four markers as a camera facing the sheet sees them (z and y) at 120 frames/s, run at
    2.5 mm spacing (a converged fine-resolution run, warpcloth's own: the sheet fit's
    continuum estimate is what it tests), noise σ = 0.02 mm."""
    denim = {"material.from_file": "denim-D"}
    times, record = sheet_paths(SHEET_MARKERS_RECORD_MM, denim)
    moved = float(np.max(np.abs(sheet_paths(2 * SHEET_MARKERS_RECORD_MM, denim)[1] - record)))
    header = (
        f"# synthetic: the shear swing of denim D (scenes/materials/denim-D.toml) for 0.3 s, run at sheet spacing "
        f"{SHEET_MARKERS_RECORD_MM:g} mm (auto's step), from which {2 * SHEET_MARKERS_RECORD_MM:g} mm differs by at "
        f"most {moved:.2g} mm; noise {SHEET_MARKERS_NOISE_MM:g} mm (scenes/data/make_denim_examples.py)"
    )
    return f"{header}\n" + sheet_marker_rows(times, record, rng, SHEET_MARKERS_NOISE_MM)


def write_record(name: str, rows: np.ndarray, fmt: tuple[str, str], header: str) -> None:
    """One two-column record next to this script, as the bundled KES examples are written."""
    np.savetxt(HERE / name, rows, fmt=fmt, delimiter=",", header=header, comments="")


def loop_record(
    name: str,
    cycle: np.ndarray,
    model: Callable[..., np.ndarray],
    parameters: tuple[float, ...],
    noise: float,
    rng: np.random.Generator,
    fmt: tuple[str, str],
    header: str,
) -> None:
    """A KES loop record: ``model(cycle, *parameters)`` along the standard ``cycle``, plus the instrument's noise."""
    loop = model(cycle, *parameters) + rng.normal(0.0, noise, len(cycle))
    write_record(name, np.column_stack([cycle, loop]), fmt, header)


def main() -> None:
    """Write the records and ``denims.json`` (published values, the models' parameters) next to this script."""
    record = {"source": SOURCE, "generator": __doc__.split("**What is ours.**")[1].split("Run ``")[0].strip()}
    fabrics = {}
    for fabric, published in PUBLISHED.items():
        rng = np.random.default_rng(SEEDS[fabric])
        shear = solve_shear(published)
        loop_record(
            f"denim_{fabric}_fb1_shear.csv",
            standard_cycle(SHEAR_PHI0_DEG, SHEAR_STEP_DEG),
            shear_force,
            tuple(shear.values()),
            SHEAR_NOISE_GF_PER_CM,
            rng,
            ("%.2f", "%.4f"),
            "shear_angle_deg,shear_force_gf_per_cm",
        )
        bending = solve_bending(published)
        loop_record(
            f"denim_{fabric}_fb2.csv",
            standard_cycle(BENDING_K0_PER_CM, BENDING_STEP_PER_CM),
            bending_moment,
            tuple(bending.values()),
            BENDING_NOISE_GF_CM_PER_CM,
            rng,
            ("%.3f", "%.5f"),
            "curvature_per_cm,moment_gf_cm_per_cm",
        )
        tensile, curve = tensile_record(published, rng)
        write_record(f"denim_{fabric}_fb1.csv", tensile, ("%.4f", "%.3f"), "strain_percent,force_gf_per_cm")
        fabrics[fabric] = {
            "published": published,
            "tensile_model": curve,
            "shear_model": {**shear, "hysteresis_alpha_per_deg": SHEAR_ALPHA_PER_DEG},
            "bending_model": {**bending, "hysteresis_alpha_cm": BENDING_ALPHA_CM},
        }
    record["fabrics"] = fabrics
    record["weight_note"] = (
        "W_printed is Table 5's number as printed with the unit mg/cm²; 94–109 mg/cm² would be 0.94–1.09 kg/m², "
        "about three times a denim's weight, so the unit or the number is in doubt and no density is derived from it"
    )
    (HERE / "denims.json").write_text(json.dumps(record, indent=1) + "\n")
    (HERE / "denim_D_shear_swing_markers.csv").write_text(sheet_markers(np.random.default_rng(3204)))


if __name__ == "__main__":
    main()
