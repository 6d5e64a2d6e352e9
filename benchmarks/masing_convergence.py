"""Mesh convergence of the hysteretic damped swing, per bending law (issue 21).

For each law (default: tagawa2003 and masing) the bundled damped swing runs at
h = 5, 2.5, 1.25, 0.625 mm with dt proportional to h (1e-5 s at 5 mm, the scene's), and
the table gives, per h: the mean log decrement and the hysteresis work at the end of the
run, their successive differences and the ratio of those, the largest tip-path difference
to the next finer h (and the observed order), and for masing the deepest reversal memory
and its overflows. With ``--twin H`` it also runs, at spacing H, a twin released 1e-12 m
further out, and prints how far the two tip paths drift apart (round-off amplification).

    python benchmarks/masing_convergence.py [--duration 3] [--laws tagawa2003 masing] [--twin 1.25]
"""

from __future__ import annotations

import argparse
import math
import platform
import time

import numpy as np

import warpcloth as wc
from warpcloth.metrics import swing_summary

SPACINGS = (5.0, 2.5, 1.25, 0.625)


def run(law: str, h: float, duration: float) -> dict:
    dt = 1e-5 * h / 5.0
    scene = wc.load_scene(
        "damped_swing",
        [
            f'material.bending_law="{law}"',
            f"strip.spacing_mm={h}",
            f"integrator.dt_s={dt}",
            f"run.duration_s={duration}",
        ],
    )
    tic = time.perf_counter()
    result = wc.simulate(scene)
    wall = time.perf_counter() - tic
    summary = swing_summary(result.t, result.probe("laser_x", 0), result.probe("tip_x", 0))
    tip = np.stack([result.probe("tip_x", 0), result.probe("tip_y", 0)], axis=-1)
    return {
        "h": h,
        "dt": dt,
        "wall": wall,
        "decrement": summary["mean_log_decrement"],
        "work": float(result.probe("hysteresis_work", 0)[-1]),
        "tip": tip,
        "t": result.t,
        "memory": result.reversal_memory,
    }


def twin(law: str, h: float, duration: float) -> float:
    """Largest tip-path difference (m) between the swing and its twin released 1e-12 m further out."""
    dt = 1e-5 * h / 5.0
    common = [
        f'material.bending_law="{law}"',
        f"strip.spacing_mm={h}",
        f"integrator.dt_s={dt}",
        f"run.duration_s={duration}",
    ]
    scenes = [wc.load_scene("damped_swing", [*common, f"release.hold_x_mm={x!r}"]) for x in (50.0, 50.0 + 1e-9)]
    result = wc.simulate(scenes)
    return float(np.nanmax(np.abs(result.probe("tip_x", 0) - result.probe("tip_x", 1))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds after the release (default 3)")
    parser.add_argument("--laws", nargs="+", default=["tagawa2003", "masing"])
    parser.add_argument("--spacings", nargs="+", type=float, default=list(SPACINGS))
    parser.add_argument("--twin", type=float, default=None, help="also run the 1e-12 m twin at this spacing (mm)")
    args = parser.parse_args()
    print(
        f"machine: {platform.machine()}, {platform.system()}, {platform.processor() or 'cpu'}; "
        f"damped swing, {args.duration:g} s after release, dt = 1e-5 s x h / 5 mm, float64"
    )
    for law in args.laws:
        runs = [run(law, h, args.duration) for h in args.spacings]
        print(f"\n{law}")
        print(
            "  h (mm)   dt (s)    wall (s)  mean log decr   Δ decr      hyst. work (µJ)  Δ work (µJ)  "
            "tip Δ to h/2 (mm)  order  memory"
        )
        previous_tip_diff = None
        for i, r in enumerate(runs):
            d_decr = r["decrement"] - runs[i - 1]["decrement"] if i else math.nan
            d_work = (r["work"] - runs[i - 1]["work"]) * 1e6 if i else math.nan
            tip_diff, order = math.nan, math.nan
            if i + 1 < len(runs):
                fine = runs[i + 1]
                # the same output times (the probe rate does not depend on h)
                tip_diff = float(np.nanmax(np.linalg.norm(r["tip"] - fine["tip"], axis=-1))) * 1e3
                if previous_tip_diff is not None:
                    order = math.log2(previous_tip_diff / tip_diff)
                previous_tip_diff = tip_diff
            memory = r["memory"]
            mem = (
                f"deepest {max(memory['deepest'])}/{memory['capacity']}, overflows {sum(memory['overflows'])}"
                if memory
                else "-"
            )
            print(
                f"  {r['h']:6.3f}   {r['dt']:.3g}  {r['wall']:8.1f}  {r['decrement']:.5f}     {d_decr:+.2e}   "
                f"{r['work'] * 1e6:10.3f}       {d_work:+.3f}       {tip_diff:10.3f}       {order:5.2f}  {mem}"
            )
        diffs = [runs[i]["decrement"] - runs[i - 1]["decrement"] for i in range(1, len(runs))]
        works = [runs[i]["work"] - runs[i - 1]["work"] for i in range(1, len(runs))]
        if len(diffs) >= 2:
            print(
                "  ratios of successive differences: decrement "
                + ", ".join(f"{diffs[i - 1] / diffs[i]:.2f}" for i in range(1, len(diffs)))
                + "; hysteresis work "
                + ", ".join(f"{works[i - 1] / works[i]:.2f}" for i in range(1, len(works)))
            )
        if args.twin:
            print(
                f"  1e-12 m twin at h = {args.twin} mm: tip paths differ by at most "
                f"{twin(law, args.twin, args.duration):.3g} m"
            )


if __name__ == "__main__":
    main()
