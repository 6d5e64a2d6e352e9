"""The paper-faithful run: damped swing, h = 5 mm, dt = 0.1 µs, float64, 1 simulated second.

    python benchmarks/paper_faithful.py [--device cpu] [--batch 1024] [--batch-sim-time 0.01]

Times one strip for a full simulated second and a batch of strips for a shorter span;
the batch's time per simulated second is extrapolated linearly (every substep costs the
same) and printed as such.
"""

from __future__ import annotations

import argparse
import logging
import platform
import time

import warp as wp

import warpcloth as wc


def timed(batch: int, sim_time: float, device: str) -> float:
    scene = wc.load_scene(
        "damped_swing",
        ["integrator.dt_s=1e-7", "release.enabled=false", f"run.duration_s={sim_time}", "integrator.precision=float64"],
    )
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.001", "release.enabled=false"]), device=device)
    start = time.perf_counter()
    wc.simulate([scene] * batch, device=device, keep_frames=False)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--batch", type=int, default=1024)
    parser.add_argument("--batch-sim-time", type=float, default=0.01)
    args = parser.parse_args()
    wp.config.log_level = logging.WARNING
    wp.init()
    print(f"machine: {platform.machine()}, {platform.system()}, device {args.device}, warp {wp.__version__}")
    one = timed(1, 1.0, args.device)
    print(f"1 strip, 1 simulated second: {one:.1f} s wall")
    many = timed(args.batch, args.batch_sim_time, args.device)
    per_second = many / args.batch_sim_time
    print(
        f"{args.batch} strips, {args.batch_sim_time} simulated s: {many:.1f} s wall "
        f"→ {per_second:.0f} s ({per_second / 3600:.2f} h) per simulated second (extrapolated)"
    )
    print(f"per-strip cost at batch {args.batch} vs batch 1: {per_second / args.batch / one:.2f}x")


if __name__ == "__main__":
    main()
