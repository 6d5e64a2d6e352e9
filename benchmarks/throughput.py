"""Strip-steps per second of the batched kernel, by batch size (run by hand).

    python benchmarks/throughput.py [--device cpu] [--sizes 1 64 1024] [--sim-time 0.05]
                                    [--scenes damped_swing impulsive_rotation] [--precisions float64 float32]

Each row runs B copies of a bundled scene and prints strip-steps/s, node-steps/s and
the per-strip-step cost relative to batch 1 measured in the same run. The damped swing
is carried to its hold in 0.1 s and released at once (no settling), so every substep
moves the strip (carried, then swinging): a strip hanging at rest is not representative, because its
curvature changes only by rounding noise and every hinge then reverses its hysteresis
branch at every substep (masing's scalar path each time). The impulsive rotation moves from
its first step. The kernel is compiled (and cached) before timing.
"""

from __future__ import annotations

import argparse
import logging
import platform
import time

import warp as wp

import warpcloth as wc


def measure(scene_name: str, batch: int, sim_time: float, device: str, precision: str) -> tuple[float, float]:
    swinging = ["release.move_time_s=0.1", "release.settle_time_s=0.0"] if scene_name == "damped_swing" else []
    scene = wc.load_scene(scene_name, [f"run.duration_s={sim_time}", f"integrator.precision={precision}", *swinging])
    wc.simulate([scene], device=device)  # compile / warm up
    start = time.perf_counter()
    result = wc.simulate([scene] * batch, device=device, keep_frames=False)
    wall = time.perf_counter() - start
    return result.strip_steps / wall, result.strip_steps * scene.n_nodes / wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 64, 1024])
    parser.add_argument("--sim-time", type=float, default=0.05, help="simulated seconds per run")
    parser.add_argument("--scenes", nargs="+", default=["damped_swing"])
    parser.add_argument("--precisions", nargs="+", default=["float64"], choices=["float64", "float32"])
    args = parser.parse_args()
    wp.config.log_level = logging.WARNING
    wp.init()
    print(
        f"machine: {platform.processor() or platform.machine()}, {platform.system()}, device {args.device}, "
        f"warp {wp.__version__}"
    )
    for name in args.scenes:
        for precision in args.precisions:
            print(f"\n{name}, {precision}: {args.sim_time} s simulated per run")
            print(f"{'batch':>6} {'strip-steps/s':>14} {'node-steps/s':>13} {'per-strip cost vs B=1':>22}")
            base = None
            for b in args.sizes:
                rate, node_rate = measure(name, b, args.sim_time, args.device, precision)
                base = base or rate
                print(f"{b:>6} {rate:>14.3e} {node_rate:>13.3e} {base / rate:>21.2f}x")


if __name__ == "__main__":
    main()
