"""Every CPU implementation at equal accuracy, all measured in one run (issue 11, item 7).

    python benchmarks/equal_accuracy.py [--quick] [--samples 200] [--sizes 200 1024]

Equal accuracy: each scheme runs at the largest dt that keeps the free end within 0.5 % of
its excursion of the dt = 1e-7 s explicit solution over the whole run (the damped swing:
the bundled material and the two sweep variants with the largest hysteresis and the
smallest rigidity; for the elastic rows, D1 = 0). The explicit peers (NumPy, Numba) run
warpcloth's semi-implicit arithmetic (checked here against it), so they share its dt.
PyElastica (a Cosserat rod; benchmarks/pyelastica_compare.py builds the same strip as a
round rod) has no hysteretic law: it appears on the elastic strip, at its own largest
stable dt (its stability limit, set by its shear–rotation mode, lies far below where its
time-step error would matter).

Printed:
1. the equal-accuracy dt of ``semi_implicit`` and ``imex`` (hysteretic and elastic);
2. strip-steps/s and wall per simulated second for B strips at those dt: warpcloth
   semi-implicit and imex on 1 and 2 threads, NumPy, Numba on 1 and 2 threads, PyElastica
   (elastic); ratios against warpcloth semi-implicit on 1 thread at its equal-accuracy dt;
3. the bundled sweep (``--samples`` variants, 1 s record, hold replicated) at equal
   accuracy: ``wc.run_sweep`` on 2 threads with each scheme, and with the scene's own dt
   (today's default) as the baseline; the Numba peer on 2 threads; NumPy and PyElastica
   from their rates (NumPy has no hold, PyElastica no hysteresis).

Needs ``pip install -e .[bench]`` (Numba, PyElastica). Compile time is excluded (every
path is warmed up first). Run on an idle machine: the 2-thread rows need both cores.
"""

from __future__ import annotations

import argparse
import logging
import os
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
import warp as wp
from imex_defaults import error_of, in_parallel
from numba_peer import NumbaStrips, free_runs, machine, sweep_scenes, warpcloth_rate, warpcloth_wall
from numpy_baseline import NumpyStrips, displaced_start

import warpcloth as wc

TOLERANCE = 5e-3
REFERENCE_DT = 1e-7
LADDERS = {"semi_implicit": (1e-5, 2.5e-5, 5e-5), "imex": (5e-5, 1e-4, 2e-4, 4e-4, 8e-4)}
ELASTIC = ["material.hysteresis_d1_gf_cm_per_cm=0.0"]


def stepping(scheme: str, dt: float) -> list[str]:
    return [f'integrator.scheme="{scheme}"', f"integrator.dt_s={dt!r}"]


def strips_to_check(samples: int, record: float, elastic: bool) -> list[list[str]]:
    """Overrides of the strips the dt must keep within the tolerance: the bundled material,
    then (hysteretic case) the sweep variants with the largest D1 and the smallest D."""
    if elastic:
        return [ELASTIC]
    _sweep, scenes = sweep_scenes(samples, record)
    d1 = [s.material.hysteresis_d1_gf_cm_per_cm for s in scenes]
    d = [s.material.bending_rigidity_gf_cm2_per_cm for s in scenes]
    picks = [int(np.argmax(d1)), int(np.argmin(d))]
    return [[]] + [
        [
            f"material.{name}={getattr(scenes[i].material, name)!r}"
            for name in ("bending_rigidity_gf_cm2_per_cm", "hysteresis_d1_gf_cm_per_cm", "hysteresis_alpha_cm")
        ]
        + [f"damping.gamma_per_s={scenes[i].damping.gamma_per_s!r}"]
        for i in picks
    ]


def equal_accuracy_dt(strips: list[list[str]], record: float) -> dict[str, tuple[float, float]]:
    """Largest ladder dt of each scheme within the tolerance on every strip, and its worst error."""
    base = [f"run.duration_s={record!r}"]
    references = in_parallel(
        [wc.load_scene("damped_swing", [*base, *stepping("semi_implicit", REFERENCE_DT), *s]) for s in strips]
    )
    tips = [r.probe("tip_x", 0) for r in references]
    chosen = {}
    for scheme, ladder in LADDERS.items():
        for dt in ladder:
            try:
                runs = in_parallel([wc.load_scene("damped_swing", [*base, *stepping(scheme, dt), *s]) for s in strips])
            except wc.SceneError:
                print(f"  {scheme:>13} dt = {dt:8.2g} s: refused (above the scheme's stability limit)")
                break
            if any(r.diverged for r in runs):
                print(f"  {scheme:>13} dt = {dt:8.2g} s: diverged")
                break
            worst = max(error_of(r, tip) for r, tip in zip(runs, tips, strict=True))
            print(f"  {scheme:>13} dt = {dt:8.2g} s: worst |Δ tip x| / excursion {worst:.3%}")
            if worst <= TOLERANCE:
                chosen[scheme] = (dt, worst)
    return chosen


def same_arithmetic(samples: int, dt: float, x0: np.ndarray) -> tuple[float, float]:
    """Largest tip gap (m) over 0.2 s from the displaced start against warpcloth: NumPy's
    final tip (it records none before), Numba's at every probe."""
    scenes = free_runs(samples, 0.2, 2, stepping("semi_implicit", dt))
    ours = wc.simulate(scenes, initial_positions=np.repeat(x0[:, None, :], 2, axis=1), keep_frames=False)
    steps = round(0.2 / dt)
    gaps = []
    numpy_strips = NumpyStrips(scenes[0], 1, x0)
    for _ in range(steps):
        numpy_strips.step()
    gaps.append(float(np.abs(numpy_strips.x[0, -1] - [ours.probe("tip_x", 0)[-1], ours.probe("tip_y", 0)[-1]]).max()))
    peer = NumbaStrips(scenes, np.repeat(x0[:, None, :], 2, axis=1))
    peer.run()
    tx, _ty = peer.kept_tips()
    gaps.append(float(np.abs(tx[:, 0] - ours.probe("tip_x", 0)).max()))
    return gaps[0], gaps[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="40 variants, 0.3 s records, short timings")
    parser.add_argument("--samples", type=int, default=200, help="sweep variants (default 200)")
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1024])
    args = parser.parse_args()
    samples = 40 if args.quick else args.samples
    record = 0.3 if args.quick else 1.0
    budget = 0.25 if args.quick else 1.0  # target wall seconds per table cell
    cores = min(2, os.cpu_count() or 1)
    wp.config.log_level = logging.WARNING
    wp.init()
    print(
        f"machine: {machine()}; warp {wp.__version__} (cpu), numba {numba.__version__}, numpy {np.__version__}; "
        f"load average at start {os.getloadavg()[0]:.2f}"
    )
    try:
        import pyelastica_compare as pe
    except ImportError:
        pe = None
        print("PyElastica not installed (pip install -e .[bench]): its rows are left out")

    # ---- 1. the equal-accuracy dt ----
    chosen = {}
    for label, elastic in (("hysteretic (bundled)", False), ("elastic (D1 = 0)", True)):
        print(
            f"\n1. equal-accuracy dt, damped swing, {label} material, {record:g} s record; "
            f"reference semi_implicit at dt = {REFERENCE_DT:g} s"
        )
        chosen[elastic] = equal_accuracy_dt(strips_to_check(samples, record, elastic), record)
        for scheme in LADDERS:
            if scheme in chosen[elastic]:
                dt, worst = chosen[elastic][scheme]
                print(f"  → {scheme}: dt = {dt:g} s (worst {worst:.3%})")
            else:
                print(f"  → {scheme}: within {TOLERANCE:.1%} at no dt of its ladder")

    # ---- warm-up and the peers' arithmetic ----
    x0 = displaced_start(free_runs(4, 0.01, 1)[0])
    dt_semi = chosen[False]["semi_implicit"][0]
    for threads in (1, cores):
        numba.set_num_threads(threads)
        NumbaStrips(free_runs(4, 0.01, 2, stepping("semi_implicit", dt_semi)), np.repeat(x0[:, None, :], 2, 1)).run()
    for scheme in LADDERS:
        warpcloth_wall(free_runs(4, 0.002, 2, stepping(scheme, dt_semi)), x0, 1)
    gap_numpy, gap_numba = same_arithmetic(samples, dt_semi, x0)
    print(
        f"\nsame arithmetic at dt = {dt_semi:g} s, 0.2 s from a displaced start: NumPy's final tip "
        f"{gap_numpy:.1e} m, Numba's at every probe {gap_numba:.1e} m from warpcloth's"
    )

    # ---- 2. throughput at equal accuracy ----
    rows = []
    for b in args.sizes:
        cells = []
        for elastic in (False, True):
            for scheme, (dt, _worst) in chosen[elastic].items():
                extra = [*stepping(scheme, dt), *(ELASTIC if elastic else [])]
                for threads in (1, cores):
                    rate = warpcloth_rate(samples, b, max(200, int(budget * 1e6 * threads / b)), dt, x0, threads, extra)
                    cells.append((f"warpcloth {scheme}, {threads} thread{'s' * (threads > 1)}", elastic, dt, rate))
        extra = stepping("semi_implicit", dt_semi)
        numpy_steps = max(50, int(budget * 3e5 / b))
        strips = NumpyStrips(free_runs(samples, numpy_steps * dt_semi, 1, extra)[0], b, x0)
        start = time.perf_counter()
        for _ in range(numpy_steps):
            strips.step()
        cells.append(("NumPy", False, dt_semi, b * numpy_steps / (time.perf_counter() - start)))
        for threads in (1, cores):
            numba.set_num_threads(threads)
            n_steps = max(200, int(budget * 3e6 * threads / b))
            peer = NumbaStrips(free_runs(samples, n_steps * dt_semi, b, extra), np.repeat(x0[:, None, :], b, axis=1))
            start = time.perf_counter()
            peer.run(n_steps)
            cells.append(
                (
                    f"Numba, {threads} thread{'s' * (threads > 1)}",
                    False,
                    dt_semi,
                    b * n_steps / (time.perf_counter() - start),
                )
            )
        if pe is not None:
            problem = pe.make_problem()
            pe_dt = pe.largest_stable_dt(lambda dt, p=problem: pe.run_pyelastica(p, 20, dt, 0.02).stable, 2e-6)
            trace = pe.run_pyelastica(problem, 20, pe_dt, max(20, int(budget * 1.5e5 / b)) * pe_dt, n_rods=b)
            cells.append(("PyElastica (Cosserat rod)", True, pe_dt, trace.element_steps / 20 / trace.wall))
        base = next(rate for name, elastic, _dt, rate in cells if name.startswith("warpcloth semi") and not elastic)
        print(
            f"\n2. B = {b}: {'implementation':<34} {'material':<11} {'dt (s)':>8} {'strip-steps/s':>14} "
            f"{'wall per sim s':>15} {'less wall than semi 1T':>23}"
        )
        for name, elastic, dt, rate in cells:
            wall = b / (rate * dt)
            print(
                f"   {'':>6} {name:<34} {'elastic' if elastic else 'hysteretic':<11} {dt:8.2g} {rate:14.3e} "
                f"{wall:13.3g} s {rate * dt / (base * dt_semi):22.3g}×"
            )
            rows.append((b, name, elastic, dt, rate))

    # ---- 3. the bundled sweep at equal accuracy ----
    print(f"\n3. the bundled sweep, {samples} variants, {record:g} s record, hold replicated, {cores} threads")
    walls = {}
    today = sweep_scenes(samples, record)[1][0].integrator.dt_s
    for label, scheme, dt in (
        ("scene default", "semi_implicit", today),
        *((scheme, scheme, dt) for scheme, (dt, _w) in chosen[False].items()),
    ):
        sweep, _scenes = sweep_scenes(samples, record, stepping(scheme, dt))
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            wc.run_sweep(sweep, Path(tmp) / "sweep", workers=cores)
            walls[label] = time.perf_counter() - start
        print(
            f"   warpcloth {label:<14} dt = {dt:8.2g} s: {walls[label]:7.2f} s "
            f"({walls['scene default'] / walls[label]:.2f}× less than the scene default)"
        )
    _sweep, scenes = sweep_scenes(samples, record, stepping("semi_implicit", dt_semi))
    numba.set_num_threads(cores)
    start = time.perf_counter()
    NumbaStrips(scenes).run()
    numba_wall = time.perf_counter() - start
    steps = round((scenes[0].run.duration_s + scenes[0].preroll) / dt_semi)
    best = min(walls.values())
    print(
        f"   Numba {cores} threads      dt = {dt_semi:8.2g} s: {numba_wall:7.2f} s "
        f"(warpcloth's best is {best / numba_wall:.2f}× the Numba peer's wall)"
    )
    for _b, name, _elastic, dt, rate in (r for r in rows if r[0] == args.sizes[0]):
        if name == "NumPy":
            print(f"   NumPy (from its rate)  dt = {dt:8.2g} s: {samples * steps / rate:7.1f} s")
        if name.startswith("PyElastica"):
            print(
                f"   PyElastica (elastic rate; no hysteretic law) dt = {dt:.2g} s: "
                f"{samples * (scenes[0].run.duration_s + scenes[0].preroll) / dt / rate:7.0f} s"
            )
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
