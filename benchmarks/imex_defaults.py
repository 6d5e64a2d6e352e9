"""Which scheme and dt reproduce the paper's dt = 1e-7 s explicit solution of each bundled
scene within 0.5 % of the free end's excursion over the whole run, at the least wall
time, and what an implicit bending step could still gain (issue 11, items 2 and 3; run
by hand, ~6 min on 2 cores):

    python benchmarks/imex_defaults.py [--reference-dt 1e-7] [--materials default elastic]
        [--law masing] [--tolerance 2e-3] [--parts ladders library]
        [--schemes semi_implicit imex imex_trapezoidal]

1. For each scene (as bundled: the default, hysteretic material; and with D1 = 0) it runs
   the explicit reference, then each scheme at a ladder of dt (whole fractions of the probe
   interval), and
   prints the largest |Δ tip x| / excursion, the wall time per simulated second, and
   which dt is the largest within the tolerance for each scheme. Wall times are of one
   strip, one thread. A semi_implicit dt above the stretching limit is refused by the
   scene check (warpcloth.scene.check_step), not run.
2. The bound on an implicit bending step (item 2): where imex is within the tolerance at
   all (the elastic material), its largest stable dt (bisection to 2 %) — the explicit
   bending limit, ∝ h² — against the dt at which its error would reach the tolerance if
   the step stayed stable beyond it (error ∝ dt^p, p fitted to the two largest stable
   ladder points). Removing the bending limit gains at most their ratio, before paying
   for a banded solve per step; with the paper's hysteresis imex has a floor above the
   tolerance on the rotation, so nothing built on it gains there.
3. The scene dt against the stability limit of each bundled material (scenes/materials/),
   h·√(ρ_A/a1)/cos(π/4N), confirmed by 0.2 s undamped runs at 0.98 and 1.02 of it, and each scene
   with each material at the scene dt against its dt = 1e-7 s solution.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.metadata
import math
import platform
import threading
import time

import numpy as np
import warp as wp

import warpcloth as wc
from warpcloth.scene import build_batch, to_si
from warpcloth.strip import SemiImplicitEulerSolver, simulate_batch

PER_PROBE = (640, 320, 160, 64, 32, 16, 8, 6, 4, 3, 2)
"""The ladder's steps per probe interval (2.6e-6 … 8.3e-4 s at 600 Hz). Each dt divides the
interval, as auto's does: a step that does not puts every probe up to dt/2 off its time, a
first-order error of the sampling, not of the scheme."""
SCHEMES = ("semi_implicit", "imex", "imex_trapezoidal")
TOLERANCE = 5e-3
LIBRARY = ("wool90-nylon10", "cotton-broadcloth", "polyester-taffeta")


def simulate(scene: wc.Scene) -> tuple[wc.RunResult | None, float]:
    """The run and its wall seconds; None for a run that diverged."""
    started = time.perf_counter()
    result = wc.simulate(scene, on_divergence="record")
    return (None if result.diverged else result), time.perf_counter() - started


def at(scene: str, scheme: str, dt: float, extra: list[str]) -> wc.Scene:
    return wc.load_scene(scene, [f'integrator.scheme="{scheme}"', f"integrator.dt_s={dt}", *extra])


def error_of(result: wc.RunResult, tip: np.ndarray) -> float:
    return float(np.abs(result.probe("tip_x", 0) - tip).max() / np.ptp(tip))


def largest_stable(scene: wc.Scene, low: float, high: float, rel: float = 0.02) -> float:
    """Bisection between a stable ``low`` and an unstable ``high`` dt (scene checks bypassed:
    imex has no pre-run bound)."""
    while high / low > 1 + rel:
        mid = math.sqrt(low * high)
        run, _ = simulate(dataclasses.replace(scene, integrator=dataclasses.replace(scene.integrator, dt_s=mid)))
        low, high = (mid, high) if run is not None else (low, mid)
    return low


def scheme_ladders(args: argparse.Namespace) -> None:
    for scene in ("damped_swing", "impulsive_rotation"):
        for material in args.materials:
            extra = [f'material.bending_law="{args.law}"']
            extra += [] if material == "default" else ["material.hysteresis_d1_gf_cm_per_cm=0.0"]
            reference, wall = simulate(at(scene, "semi_implicit", args.reference_dt, extra))
            duration = reference.t[-1]
            tip = reference.probe("tip_x", 0)
            print(f"\n{scene}, {material} material: reference dt = {args.reference_dt:g} s took {wall:.1f} s")
            print(f"{'scheme':>14} {'dt (s)':>8} {'max |Δtip| / excursion':>24} {'wall per sim s':>15}")
            best, stable = {}, {}
            default, default_wall = simulate(at(scene, "semi_implicit", wc.load_scene(scene).integrator.dt_s, extra))
            scene_wall = {scene: default_wall / duration}
            print(
                f"{'(scene dt)':>14} {wc.load_scene(scene).integrator.dt_s:8.2g} {error_of(default, tip):24.3%} "
                f"{default_wall / duration:13.3f} s"
            )
            ladder = [wc.load_scene(scene).output_interval / k for k in PER_PROBE]
            for scheme in args.schemes:
                for dt in ladder:
                    try:
                        result, wall = simulate(at(scene, scheme, dt, extra))
                    except wc.SceneError as refused:
                        print(f"{scheme:>14} {dt:8.2g} {'refused':>24}  ({str(refused).split(':')[1].strip()})")
                        break
                    if result is None:
                        print(f"{scheme:>14} {dt:8.2g} {'diverged':>24}")
                        stable.setdefault(scheme, []).append((dt, None))
                        break
                    error = error_of(result, tip)
                    stable.setdefault(scheme, []).append((dt, error))
                    print(f"{scheme:>14} {dt:8.2g} {error:24.3%} {wall / duration:13.3f} s")
                    if error <= args.tolerance:
                        best[scheme] = (dt, wall / duration)
            for scheme, (dt, wall) in best.items():
                print(
                    f"  {scheme}: largest dt within {args.tolerance:.1%}: {dt:g} s ({wall:.3f} s wall per simulated s)"
                )
            for implicit in ("imex", "imex_trapezoidal"):
                if "semi_implicit" in best and implicit in best:
                    print(
                        f"  {implicit} at its dt against semi_implicit at the scene's dt: "
                        f"{scene_wall[scene] / best[implicit][1]:.1f}x less wall per simulated s"
                    )
            if not best:
                print(f"  no scheme within {args.tolerance:.1%} on this ladder")
            if "imex" in best and "imex" in stable:
                implicit_bending_bound(at(scene, "imex", ladder[0], extra), stable["imex"])
            else:
                print("  implicit bending: cannot help; imex itself is never within the tolerance here")


def implicit_bending_bound(scene: wc.Scene, ladder: list[tuple[float, float | None]]) -> None:
    """Item 2: how much larger a step an implicit bending update could take at the tolerance."""
    runs = [(dt, e) for dt, e in ladder if e is not None]
    unstable = next((dt for dt, e in ladder if e is None), None)
    if unstable is None or len(runs) < 2:
        print("  implicit bending: imex stable over the whole ladder; its accuracy, not bending, limits dt")
        return
    limit = largest_stable(scene, runs[-1][0], unstable)
    (dt1, e1), (dt2, e2) = runs[-2], runs[-1]
    order = math.log(e2 / e1) / math.log(dt2 / dt1)
    if not order > 0:
        print(
            f"  implicit bending: imex is stable to {limit:.3g} s and its error does not grow with dt there "
            f"({e1:.3%} → {e2:.3%}): no extrapolation"
        )
        return
    at_tolerance = dt2 * (TOLERANCE / e2) ** (1.0 / order)
    print(
        f"  implicit bending: imex is stable to {limit:.3g} s (explicit bending, ∝ h²); its error grows as "
        f"dt^{order:.2f} ({e1:.3%} → {e2:.3%}), reaching {TOLERANCE:.1%} at ≈ {at_tolerance:.3g} s: an implicit "
        f"bending step could take about {at_tolerance / limit:.2f}× larger steps at equal accuracy (extrapolated), "
        "before the cost of its banded solve"
    )


def in_parallel(scenes: list[wc.Scene]) -> list[wc.RunResult]:
    """One strip a Python thread (Warp releases the GIL during a launch), each its own run."""
    results: list[wc.RunResult | None] = [None] * len(scenes)

    def one(i: int) -> None:
        results[i] = wc.simulate(scenes[i], on_divergence="record", keep_frames=False, threads=1)

    workers = [threading.Thread(target=one, args=(i,)) for i in range(len(scenes))]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    return results


def library_limits(reference_dt: float) -> None:
    print(
        "\nthe scene dt against each bundled material's stretching limit h·√(ρ_A/a1)/cos(π/4N) "
        "(semi_implicit), confirmed by 0.2 s undamped runs without the release (the rotation's clamp drive "
        "kept) at 0.98 and 1.02 of it; "
        f"and the scene as bundled with that material at its dt against dt = {reference_dt:g} s"
    )
    print(
        f"{'scene':>20} {'material':>20} {'limit (s)':>10} {'scene dt / limit':>17} {'0.98×':>8} {'1.02×':>9} "
        f"{'error at scene dt':>18}"
    )
    for scene in ("damped_swing", "impulsive_rotation"):
        full = [wc.load_scene(scene, [f'material.from_file="{material}"']) for material in LIBRARY]
        references = in_parallel(
            [dataclasses.replace(s, integrator=dataclasses.replace(s.integrator, dt_s=reference_dt)) for s in full]
        )
        runs = in_parallel(full)
        for material, run, reference in zip(LIBRARY, runs, references, strict=True):
            base = wc.load_scene(
                scene,
                [
                    f'material.from_file="{material}"',
                    "release.enabled=false",
                    "damping.gamma_per_s=0.0",
                    "run.duration_s=0.2",
                ],
            )
            limit = SemiImplicitEulerSolver.step_limit(
                to_si(base.material), base.spacing, base.n_nodes - base.n_clamped
            )
            batch = build_batch([base])  # the simulation core takes any dt; the scene layer refuses
            outcome = []
            for fraction in (0.98, 1.02):
                solver = SemiImplicitEulerSolver(batch.model, dt=fraction * limit)
                hanging = simulate_batch(
                    batch.model,
                    batch.control,
                    solver,
                    batch.recorder,
                    on_divergence="record",
                    keep_frames=False,
                    threads=1,
                )
                outcome.append("diverged" if hanging.diverged else "stable")
            error = error_of(run, reference.probe("tip_x", 0)) if not run.diverged else math.nan
            print(
                f"{scene:>20} {material:>20} {limit:10.3g} {base.integrator.dt_s / limit:17.2f} "
                f"{outcome[0]:>8} {outcome[1]:>9} {error:17.3%}"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference-dt", type=float, default=1e-7)
    parser.add_argument("--materials", nargs="+", default=["default", "elastic"], choices=["default", "elastic"])
    parser.add_argument("--law", default="tagawa2003", help="the bending law of every run (default tagawa2003)")
    parser.add_argument(
        "--tolerance",
        type=float,
        default=TOLERANCE,
        help=f"largest |Δ tip x| / excursion accepted (default {TOLERANCE:g})",
    )
    parser.add_argument("--parts", nargs="+", default=["ladders", "library"], choices=["ladders", "library"])
    parser.add_argument("--schemes", nargs="+", default=list(SCHEMES), choices=SCHEMES)
    args = parser.parse_args()
    version = importlib.metadata.version("warpcloth")
    print(
        f"{platform.processor() or platform.machine()}, warpcloth {version}, Warp {wp.__version__}, "
        "one strip, one thread"
    )
    if "ladders" in args.parts:
        scheme_ladders(args)
    if "library" in args.parts:
        library_limits(args.reference_dt)


if __name__ == "__main__":
    main()
