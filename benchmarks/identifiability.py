"""Which of (D, D1, γ, K_rest, grip factor, ℓ_g) the experiments determine (issue 28).

Synthetic truth: the bundled material with a set K_rest = 0.1 1/cm and a grip zone of
10 mm at 3× the rigidity. Three experiments, each as the fit would see it:

- swing: the damped swing's laser trace (hold and release), 300 Hz, σ = 0.2 mm;
- rotation: the impulsive rotation's markers every 10 mm at 60 frames/s, σ = 0.3 mm,
  the strip settled freely first (``release.hold_free_end = false``: its own hanging shape);
- static: the settled hanging strip's markers (a still from the video), σ = 0.3 mm;
- cantilever: the strip turned horizontal by the clamp (π/2 over 0.5 s) and settled, the
  bending-length test's pose, its markers over the last 0.1 s of 2.5 s, σ = 0.3 mm.

For each experiment and each combination (their residuals stacked, as one fit of all of
them would stack them) it prints the Gauss–Newton σ of every parameter and the pairs
correlated beyond 0.95 (the fit's ``not_identifiable`` verdict), from the Jacobian at the
truth (warpcloth.calibrate.motion_fit.weighted_jacobian and identifiability), then the full correlation matrices.

    python benchmarks/identifiability.py [--rotation-spacing 2.5]
"""

from __future__ import annotations

import argparse
import copy
import itertools
import platform
import time

import numpy as np
import warp as wp

import warpcloth as wc
from warpcloth.calibrate.motion_fit import identifiability, weighted_jacobian
from warpcloth.io.measured import LaserTrace, TrackedShapes
from warpcloth.scene import read_scene_file, set_field

TRUTH = {"strip.rest_curvature_per_cm": 0.1, "clamp.grip_length_mm": 10.0, "clamp.grip_bending_factor": 3.0}
NAMES = ("D", "D1", "gamma", "K_rest", "grip_factor", "grip_length")
SHORT = {
    "material.bending_rigidity_gf_cm2_per_cm": "D",
    "material.hysteresis_d1_gf_cm_per_cm": "D1",
    "damping.gamma_per_s": "γ",
    "strip.rest_curvature_per_cm": "K_rest",
    "clamp.grip_bending_factor": "grip",
    "clamp.grip_length_mm": "ℓ_g",
}


def raw(name: str, fields: dict) -> dict:
    """The bundled scene ``name`` with ``fields`` (dotted) and the truth set."""
    data = read_scene_file(name)
    for key, value in {**fields, **TRUTH}.items():
        set_field(data, key, value)
    return data


def markers(result: wc.RunResult, scene: wc.Scene, frames: slice = slice(None)) -> TrackedShapes:
    """Markers every 10 mm below the clamp edge at the recorded frames (noise-free: the
    Jacobian does not depend on the noise, only its weight does)."""
    nc, h = scene.n_clamped, scene.spacing
    rows = [
        (f, t, s, *result.frames[f, 0, nc - 1 + round(s / h)])
        for f, t in list(enumerate(result.frame_times))[frames]
        for s in np.arange(0.01, 0.1001, 0.01)
    ]
    d = np.array(rows)
    return TrackedShapes(d[:, 0].astype(int), d[:, 1], d[:, 2], d[:, 3], d[:, 4])


def experiments(rotation_spacing: float) -> dict[str, tuple[dict, object, float]]:
    """name → (raw scene, its synthetic measurement, σ_m in m)."""
    swing = raw("damped_swing", {"release.settle_time_s": 0.5, "run.duration_s": 1.2})
    result = wc.simulate(wc.scene_from_dict(copy.deepcopy(swing)))
    trace = LaserTrace(result.t[::2], result.probe("laser_x", 0)[::2])
    settle = {
        "release.enabled": True,
        "release.hold_free_end": False,
        "release.move_time_s": 0.1,
        "release.settle_time_s": 1.0,
    }
    rotation = raw("impulsive_rotation", {**settle, "run.duration_s": 0.3, "strip.spacing_mm": rotation_spacing})
    scene = wc.scene_from_dict(copy.deepcopy(rotation))
    rotated = markers(wc.simulate(scene), scene)
    static = raw("damped_swing", {**settle, "run.duration_s": 0.1})
    scene = wc.scene_from_dict(copy.deepcopy(static))
    still = markers(wc.simulate(scene), scene)
    turn, ramp = np.pi / 2, 0.5  # a cubic smoothstep to horizontal, as tests/test_elastica.py turns it
    cantilever = raw(
        "damped_swing",
        {"release.enabled": False, "run.duration_s": 2.5, "damping.gamma_per_s": 5.0, "clamp.motion": "piecewise"},
    )
    cantilever["clamp"]["segments"] = [
        {
            "t_start_s": 0.0,
            "t_end_s": ramp,
            "theta_coefficients_si": [0.0, 0.0, 3 * turn / ramp**2, -2 * turn / ramp**3],
        }
    ]
    scene = wc.scene_from_dict(copy.deepcopy(cantilever))
    horizontal = markers(wc.simulate(scene), scene, slice(-7, None))
    return {
        "swing": (swing, trace, 2e-4),
        "rotation": (rotation, rotated, 3e-4),
        "static": (static, still, 3e-4),
        "cantilever": (cantilever, horizontal, 3e-4),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rotation-spacing", type=float, default=2.5, help="h of the rotation (mm; the scene's 2.5)")
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {platform.system()}, warp {wp.__version__}, float64, truth {TRUTH}")
    tic = time.perf_counter()
    runs = experiments(args.rotation_spacing)
    combos = [c for r in range(1, len(runs) + 1) for c in itertools.combinations(runs, r)]
    blocks = {
        name: weighted_jacobian(base, measured, noise, list(NAMES)) for name, (base, measured, noise) in runs.items()
    }
    tables = {combo: identifiability([blocks[name] for name in combo]) for combo in combos}
    print(f"({time.perf_counter() - tic:.0f} s)\n")
    header = f"{'experiments':<40}" + "".join(f"{SHORT[f]:>10}" for f in tables[combos[0]].names)
    print(
        "σ of each parameter (D, D1 in gf·cm(²)/cm, γ in 1/s, K_rest in 1/cm, ℓ_g in mm) and the pairs the data "
        "do not separate (|correlation| > 0.95):\n"
    )
    print(header)
    for combo, table in tables.items():
        pairs = ", ".join(f"{SHORT[a]}–{SHORT[b]} {c:+.3f}" for a, b, c in table.not_identifiable) or "none"
        sigmas = "".join(f"{table.sigma[f]:>10.3g}" for f in table.names)
        print(f"{' + '.join(combo):<40}{sigmas}   not identifiable: {pairs}")
    for combo, table in tables.items():
        print(f"\n{' + '.join(combo)}:\n{table.table()}")


if __name__ == "__main__":
    main()
