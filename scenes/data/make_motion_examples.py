"""Generate the bundled example measurements for ``warpcloth fit`` and ``warpcloth clamp fit-angle``.

    python scenes/data/make_motion_examples.py      # about 4 minutes on one core

They are synthetic: the paper's measured curves are not in its text, so each file is a
warpcloth run with *known* parameters, sampled as the instrument would, plus seeded
Gaussian noise of a stated size. A lab record is of the continuum, not of a mesh, so each
motion is run on a mesh far finer than any a fit uses (the strips at h = 0.625 mm, 4× to
8× finer than the scenes' 2.5 and 5 mm; the sheet at 1.25 mm, 8× finer than the 10 mm its
guide fit uses), and the script runs each at half that spacing too and writes the largest
difference into the file's header: each is a small fraction of the noise (the evidence
that the record is the continuum's to within its noise). A fit of these files at the
scenes' spacings must find the truth within its σ_total only because it extrapolates to
h → 0 (warpcloth.calibrate.motion_fit.continuum); a fit at the scene's spacing alone is
several σ off (docs/calibration.md, "The node spacing").

- ``damped_swing_laser.csv``: the bundled damped swing (masing) with γ = 0.55 /s and
  D1 = 0.025 gf·cm/cm; laser-line displacement sampled at 300 Hz for 1.5 s; noise
  σ = 0.2 mm.
- ``impulsive_rotation_shapes.csv``: the impulsive rotation (0.3 s, masing) with the
  rotation centre 4.0 mm above the clamp's lowest point and γ = 0.8 /s; 11 markers every
  10 mm along the strip tracked at 60 frames/s; noise σ = 0.3 mm per coordinate; the
  camera clock starts 4 ms after the clamp (so ``--align-start`` has something to find).
- ``impulsive_rotation_encoder.csv``: the bundled scene's θ(t) (at rest until t = 0,
  3.2e4 t⁴ to 0.05 s, then 16 rad/s to 0.12 s, then held) sampled at 1 kHz from −0.03 s
  to 0.2 s, in degrees, the encoder reading 0.25° at rest; noise σ = 0.1° (no mesh: the
  clamp's own motion).
- ``shear_swing_markers.csv``: the bundled sheet's shear swing for 0.3 s with the shear
  rigidity G = 1.2 gf/(cm·°) (the material file says 0.8); its four markers as a camera
  facing the sheet sees them (z and y) at 120 frames/s; noise σ = 0.02 mm per coordinate
  (its own seed, so the strip files above stay as they were).
"""

from __future__ import annotations

import copy
import logging
from pathlib import Path

import numpy as np
import warp as wp

import warpcloth as wc
from warpcloth.scene import read_scene_file, set_field

HERE = Path(__file__).parent
SWING_TRUTH = {"damping.gamma_per_s": 0.55, "material.hysteresis_d1_gf_cm_per_cm": 0.025}
ROTATION_TRUTH = {"clamp.rotation_centre_dy_mm": 4.0, "damping.gamma_per_s": 0.8}
SHEET_FIT = {"sheet.spacing_warp_mm": 10.0, "sheet.spacing_weft_mm": 10.0, "run.duration_s": 0.3}
"""The shear swing's resolution for the fit of its example the guide runs."""
SHEET_TRUTH = {"shear.rigidity_gf_per_cm_deg": 1.2}
STRIP_RECORD_MM = 0.625
"""The strips' records' spacing (h = 0.3125 mm moves them by the headers' amounts)."""
SHEET_RECORD_MM = 1.25
"""The sheet's record's spacing (h = 2.5 mm differs from it by the header's amount)."""
FINE = {"integrator.scheme": "imex", "integrator.dt_s": "auto"}
"""imex at auto's step, within 0.07 % of the converged solution (docs/model.md §9.6)."""


def scene_with(name: str, fields: dict) -> wc.Scene:
    """A bundled scene with some fields replaced."""
    data = read_scene_file(name)
    for key, value in fields.items():
        set_field(data, key, value)
    return wc.scene_from_dict(copy.deepcopy(data))


def provenance(truth: dict, spacing: str, h: float, moved_mm: float, noise_mm: float) -> str:
    """The header line saying what made a record and how converged its mesh is."""
    return (
        f"# synthetic: {truth}; run at {spacing} = {h:g} mm (masing, imex at auto's step), which "
        f"{spacing} = {h / 2:g} mm moves by at most {moved_mm:.2g} mm ({moved_mm / noise_mm:.2g} of the "
        f"noise); noise {noise_mm:g} mm (scenes/data/make_motion_examples.py)"
    )


def laser_signal(h: float) -> tuple[np.ndarray, np.ndarray]:
    """The damped swing's laser-line displacement (mm) at 300 Hz, run at spacing ``h`` mm."""
    scene = scene_with("damped_swing", SWING_TRUTH | FINE | {"run.duration_s": 1.5, "strip.spacing_mm": h})
    result = wc.simulate(scene)
    return result.t[::2], result.probe("laser_x", 0)[::2] * 1e3


def laser_trace(rng: np.random.Generator) -> str:
    """The damped swing's laser-line displacement, 300 Hz, σ = 0.2 mm."""
    t, x = laser_signal(STRIP_RECORD_MM)
    moved = float(np.max(np.abs(laser_signal(STRIP_RECORD_MM / 2)[1] - x)))
    x = x + rng.normal(0, 0.2, len(t))
    rows = "\n".join(f"{ti:.6f},{xi:.4f}" for ti, xi in zip(t, x, strict=True))
    header = provenance(SWING_TRUTH, "strip.spacing_mm", STRIP_RECORD_MM, moved, 0.2)
    return f"{header}\nt_s,x_mm\n{rows}\n"


def marker_paths(h: float) -> tuple[np.ndarray, np.ndarray]:
    """Frame times and markers every 10 mm, s = 0 … 100 mm ([frame, marker, xy], mm) of the
    rotation run at spacing ``h`` mm (a divisor of 10)."""
    scene = scene_with("impulsive_rotation", ROTATION_TRUTH | FINE | {"run.duration_s": 0.3, "strip.spacing_mm": h})
    result = wc.simulate(scene)
    nodes = [scene.n_clamped - 1 + round(s_mm / h) for s_mm in range(0, 101, 10)]
    return result.frame_times, result.frames[:, 0, nodes] * 1e3


def tracked_shapes(rng: np.random.Generator) -> str:
    """Markers every 10 mm on the rotating strip at 60 frames/s, σ = 0.3 mm, clock 4 ms late."""
    times, paths = marker_paths(STRIP_RECORD_MM)
    moved = float(np.max(np.abs(marker_paths(STRIP_RECORD_MM / 2)[1] - paths)))
    rows = []
    for f, t in enumerate(times):
        if t < 0.004:
            continue
        for k, s_mm in enumerate(range(0, 101, 10)):
            x, y = paths[f, k] + rng.normal(0, 0.3, 2)
            rows.append(f"{f},{t - 0.004:.6f},{s_mm},{x:.4f},{y:.4f}")
    header = provenance(ROTATION_TRUTH, "strip.spacing_mm", STRIP_RECORD_MM, moved, 0.3)
    return f"{header}, camera clock 4 ms late\nframe,t_s,s_mm,x_mm,y_mm\n" + "\n".join(rows) + "\n"


def encoder(rng: np.random.Generator) -> str:
    """The bundled rotation's θ(t) at 1 kHz in degrees from 30 ms before the start, the
    encoder reading 0.25° at rest, σ = 0.1°."""
    t = np.round(np.arange(-0.03, 0.2, 1e-3), 6)
    tau = np.clip(t, 0.0, None)
    theta = np.where(tau < 0.05, 3.2e4 * tau**4, 0.2 + 16.0 * (np.minimum(tau, 0.12) - 0.05))
    degrees = 0.25 + np.degrees(theta) + rng.normal(0, 0.1, len(t))
    rows = "\n".join(f"{ti:.4f},{di:.4f}" for ti, di in zip(t, degrees, strict=True))
    return (
        "# synthetic: at rest (reading 0.25 deg) until t = 0, then 3.2e4 t^4 to 0.05 s, 16 rad/s to 0.12 s, "
        f"stopped; noise 0.1 deg (scenes/data/make_motion_examples.py)\nt_s,theta_deg\n{rows}\n"
    )


def sheet_paths(h: float, fields: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Times and the shear swing's markers' (y, z) at 120 frames/s ([sample, marker, yz],
    mm), the sheet run for 0.3 s at spacing ``h`` mm along warp and weft with ``fields``
    (default :data:`SHEET_TRUTH`)."""
    from warpcloth.runs import simulate
    from warpcloth.scene.sheet_build import load_sheet_scene

    fields = (SHEET_TRUTH if fields is None else fields) | {
        "run.duration_s": 0.3,
        "sheet.spacing_warp_mm": h,
        "sheet.spacing_weft_mm": h,
    }
    result = simulate(load_sheet_scene("shear_swing", fields))
    return result.t[::5], result.markers[::5, 0, :, 1:] * 1e3


def sheet_marker_rows(times: np.ndarray, paths: np.ndarray, rng: np.random.Generator, sigma_mm: float) -> str:
    """The rows ``t_s,marker,z_mm,y_mm`` (with their header line) of a sheet's markers as a
    camera facing the sheet sees them, each coordinate with Gaussian noise ``sigma_mm``."""
    rows = []
    for t, sample in zip(times, paths, strict=True):
        for marker, (y, z) in enumerate(sample):
            z, y = np.array([z, y]) + rng.normal(0, sigma_mm, 2)
            rows.append(f"{t:.6f},{marker},{z:.5f},{y:.5f}")
    return "t_s,marker,z_mm,y_mm\n" + "\n".join(rows) + "\n"


def sheet_markers(rng: np.random.Generator) -> str:
    """The shear swing's four markers, z and y, at 120 frames/s, σ = 0.02 mm."""
    times, paths = sheet_paths(SHEET_RECORD_MM)
    moved = float(np.max(np.abs(sheet_paths(2 * SHEET_RECORD_MM)[1] - paths)))
    header = (
        f"# synthetic: the shear swing (masing) with {SHEET_TRUTH | {'run.duration_s': 0.3}}; run at sheet spacing "
        f"{SHEET_RECORD_MM:g} mm (auto's step), from which {2 * SHEET_RECORD_MM:g} mm differs by at most "
        f"{moved:.2g} mm ({moved / 0.02:.2g} of the noise); noise 0.02 mm (scenes/data/make_motion_examples.py)"
    )
    return f"{header}\n" + sheet_marker_rows(times, paths, rng, 0.02)


def main() -> None:
    """Write the four files next to this script."""
    wp.config.log_level = logging.WARNING
    rng = np.random.default_rng(2026)
    (HERE / "damped_swing_laser.csv").write_text(laser_trace(rng))
    (HERE / "impulsive_rotation_shapes.csv").write_text(tracked_shapes(rng))
    (HERE / "impulsive_rotation_encoder.csv").write_text(encoder(rng))
    (HERE / "shear_swing_markers.csv").write_text(sheet_markers(np.random.default_rng(2027)))


if __name__ == "__main__":
    main()
