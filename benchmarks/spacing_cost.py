"""What the node spacing costs a motion fit (issue 22): a measurement made by a converged
fine simulation, fitted at coarser spacings.

The bundled impulsive rotation under the masing law (mesh-independent hysteresis) with
γ = 0.4 /s, rotation centre dy = 2.8 mm, D1 = 0.05 gf·cm/cm is simulated at h = 1.25 mm
(dt = 2.5e-6 s); 11 markers every 10 mm at 60 frames/s for 0.25 s get σ = 0.1 mm of noise.
The script first shows the reference is converged (the markers' largest change when dt
halves, and when h halves to 0.625 mm), then fits γ, dy and D1 at each ``--spacings`` (dt
in proportion to h) with the noise given, and prints each parameter's error in % and in
its σ, the RMS and the verdict.

    python benchmarks/spacing_cost.py [--spacings 5 2.5 1.25]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from conftest import SPACING_TRUTH, fine_rotation_markers, rotation_scene_data  # noqa: E402

from warpcloth.calibrate.motion_fit import fit_motion, free_parameters  # noqa: E402
from warpcloth.scene import scene_from_dict  # noqa: E402


def main() -> None:
    """Print the convergence of the reference and the fit at each spacing."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spacings", nargs="+", type=float, default=[5.0, 2.5, 1.25])
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}")
    reference = fine_rotation_markers(noise_m=0.0)
    for label, other in (
        ("dt / 2", fine_rotation_markers(noise_m=0.0, dt_factor=0.5)),
        ("h = 0.625 mm", fine_rotation_markers(0.625, noise_m=0.0)),
    ):
        change = np.hypot(other.x - reference.x, other.y - reference.y).max()
        print(f"reference h = 1.25 mm, dt = 2.5e-6 s: the markers move at most {change * 1e3:.4f} mm with {label}")
    measured = fine_rotation_markers()
    for h in args.spacings:
        base = rotation_scene_data(h)
        free = free_parameters("gamma,rotation_centre_dy_mm,D1", scene_from_dict(base))
        started = time.perf_counter()
        fit = fit_motion(base, measured, free, progress=False, noise=1e-4)
        errors = ", ".join(
            f"{name.split('.')[-1]} {value:.5g} ± {fit.sigma[name]:.2g} "
            f"({(value / SPACING_TRUTH[name] - 1) * 100:+.2f} %, "
            f"{(value - SPACING_TRUTH[name]) / fit.sigma[name]:+.1f} σ)"
            for name, value in fit.parameters.items()
        )
        print(
            f"h = {h:g} mm: {errors}; RMS {fit.rms * 1e3:.4f} mm ({fit.rms / 1e-4:.2f}× the noise), {fit.status}, "
            f"{time.perf_counter() - started:.0f} s"
        )


if __name__ == "__main__":
    main()
