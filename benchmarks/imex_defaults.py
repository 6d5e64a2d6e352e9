"""Which scheme and dt reproduce the paper's dt = 1e-7 s explicit solution of each bundled
scene within 0.5 % of the free end's excursion over the whole run, at the least wall
time (issue 11, item 3; run by hand, ~2 min on 2 cores):

    python benchmarks/imex_defaults.py [--reference-dt 1e-7] [--materials default elastic]

For each scene (as bundled: the default, hysteretic material; and with D1 = 0) it runs
the explicit reference, then ``semi_implicit`` and ``imex`` at a ladder of dt, and prints
the largest |Δ tip x| / excursion, the wall time per simulated second, and which dt is
the largest within the tolerance for each scheme. Wall times are of one strip, one thread.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import warpcloth as wc

LADDER = (2.5e-6, 5e-6, 1e-5, 2.5e-5, 5e-5, 1e-4, 2e-4, 4e-4, 8e-4)
TOLERANCE = 5e-3


def simulate(scene: str, scheme: str, dt: float, extra: list[str]) -> tuple[wc.RunResult | None, float]:
    started = time.perf_counter()
    result = wc.simulate(wc.load_scene(scene, [f'integrator.scheme="{scheme}"', f"integrator.dt_s={dt}", *extra]),
                         on_divergence="record")
    return (None if result.diverged else result), time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference-dt", type=float, default=1e-7)
    parser.add_argument("--materials", nargs="+", default=["default", "elastic"], choices=["default", "elastic"])
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, Warp {wc.__version__ if hasattr(wc, '__version__') else ''}")
    for scene in ("damped_swing", "impulsive_rotation"):
        for material in args.materials:
            extra = [] if material == "default" else ["material.hysteresis_d1_gf_cm_per_cm=0.0"]
            reference, wall = simulate(scene, "semi_implicit", args.reference_dt, extra)
            duration = reference.t[-1]
            tip = reference.probe("tip_x", 0)
            print(f"\n{scene}, {material} material: reference dt = {args.reference_dt:g} s took {wall:.1f} s")
            print(f"{'scheme':>14} {'dt (s)':>8} {'max |Δtip| / excursion':>24} {'wall per sim s':>15}")
            best = {}
            for scheme in ("semi_implicit", "imex"):
                for dt in LADDER:
                    result, wall = simulate(scene, scheme, dt, extra)
                    if result is None:
                        print(f"{scheme:>14} {dt:8.2g} {'diverged':>24}")
                        break
                    error = np.abs(result.probe("tip_x", 0) - tip).max() / np.ptp(tip)
                    print(f"{scheme:>14} {dt:8.2g} {error:24.3%} {wall / duration:13.3f} s")
                    if error <= TOLERANCE:
                        best[scheme] = (dt, wall / duration)
            for scheme, (dt, wall) in best.items():
                print(f"  {scheme}: largest dt within {TOLERANCE:.1%}: {dt:g} s ({wall:.3f} s wall per simulated s)")
            if not best:
                print(f"  no scheme within {TOLERANCE:.1%} on this ladder")


if __name__ == "__main__":
    main()
