"""Generate the bundled example measurements for ``warpcloth fit`` and ``warpcloth clamp fit-angle``.

    python scenes/data/make_motion_examples.py

They are synthetic: the paper's measured curves are not in its text, so each file is a
warpcloth run of a bundled scene with *known* parameters, sampled as the instrument
would, plus seeded Gaussian noise of a stated size. The runs use the scenes' default edge
model (``clamp.edge_hinge = "second_order"``). A fit of these files should return
the parameters below within its reported uncertainty.

- ``damped_swing_laser.csv``: the bundled damped swing with γ = 0.55 /s and
  D1 = 0.025 gf·cm/cm; laser-line displacement sampled at 300 Hz for
  1.5 s; noise σ = 0.2 mm.
- ``impulsive_rotation_shapes.csv``: the impulsive rotation (0.3 s) with the rotation
  centre 4.0 mm above the clamp's lowest point and γ = 0.8 /s; 11 markers every 10 mm
  along the strip tracked at 60 frames/s; noise σ = 0.3 mm per coordinate; the camera
  clock starts 4 ms after the clamp (so ``--align-start`` has something to find).
- ``impulsive_rotation_encoder.csv``: the bundled scene's θ(t) (at rest until t = 0,
  3.2e4 t⁴ to 0.05 s, then 16 rad/s to 0.12 s, then held) sampled at 1 kHz from −0.03 s
  to 0.2 s, in degrees, the encoder reading 0.25° at rest; noise σ = 0.1°.
- ``shear_swing_markers.csv``: the bundled sheet's shear swing at a 10 mm spacing for
  0.3 s, with the shear rigidity G = 1.2 gf/(cm·°) (the material file says 0.8); its four markers as a camera facing
  the sheet sees them (z and y) at 120 frames/s; noise σ = 0.02 mm per coordinate
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
"""The shear swing's resolution for its example (and for the fit of it the guide runs)."""
SHEET_TRUTH = {"shear.rigidity_gf_per_cm_deg": 1.2}


def scene_with(name: str, fields: dict) -> wc.Scene:
    """A bundled scene with some fields replaced."""
    data = read_scene_file(name)
    for key, value in fields.items():
        set_field(data, key, value)
    return wc.scene_from_dict(copy.deepcopy(data))


def laser_trace(rng: np.random.Generator) -> str:
    """The damped swing's laser-line displacement, 300 Hz, σ = 0.2 mm."""
    scene = scene_with("damped_swing", SWING_TRUTH | {"run.duration_s": 1.5})
    result = wc.simulate(scene)
    t, x = result.t[::2], result.probe("laser_x", 0)[::2] * 1e3 + rng.normal(0, 0.2, len(result.t[::2]))
    rows = "\n".join(f"{ti:.6f},{xi:.4f}" for ti, xi in zip(t, x, strict=True))
    return f"# synthetic: {SWING_TRUTH}, noise 0.2 mm (scenes/data/make_motion_examples.py)\nt_s,x_mm\n{rows}\n"


def tracked_shapes(rng: np.random.Generator) -> str:
    """Markers every 10 mm on the rotating strip at 60 frames/s, σ = 0.3 mm, clock 4 ms late."""
    scene = scene_with("impulsive_rotation", ROTATION_TRUTH | {"run.duration_s": 0.3})
    result = wc.simulate(scene)
    nc, h = scene.n_clamped, scene.strip.spacing_mm
    rows = []
    for f, t in enumerate(result.frame_times):
        if t < 0.004:
            continue
        for s_mm in range(0, 101, 10):
            x, y = result.frames[f, 0, nc - 1 + round(s_mm / h)] * 1e3 + rng.normal(0, 0.3, 2)
            rows.append(f"{f},{t - 0.004:.6f},{s_mm},{x:.4f},{y:.4f}")
    return (
        f"# synthetic: {ROTATION_TRUTH}, noise 0.3 mm, camera clock 4 ms late "
        "(scenes/data/make_motion_examples.py)\nframe,t_s,s_mm,x_mm,y_mm\n" + "\n".join(rows) + "\n"
    )


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


def sheet_markers(rng: np.random.Generator) -> str:
    """The shear swing's four markers, z and y, at 120 frames/s, σ = 0.02 mm."""
    from warpcloth.runs import simulate_sheet
    from warpcloth.scene.sheet_build import load_sheet_scene

    result = simulate_sheet(load_sheet_scene("shear_swing", SHEET_FIT | SHEET_TRUTH))
    rows = []
    for k in range(0, len(result.t), 5):
        for marker, (_x, y, z) in enumerate(result.markers[k, 0] * 1e3):
            z, y = np.array([z, y]) + rng.normal(0, 0.02, 2)
            rows.append(f"{result.t[k]:.6f},{marker},{z:.5f},{y:.5f}")
    return (
        f"# synthetic: the shear swing with {SHEET_FIT | SHEET_TRUTH}, noise 0.02 mm "
        "(scenes/data/make_motion_examples.py)\nt_s,marker,z_mm,y_mm\n" + "\n".join(rows) + "\n"
    )


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
