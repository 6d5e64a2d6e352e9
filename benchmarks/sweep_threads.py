"""Sweep wall time by thread count, in one process (issue 11 item 4).

    python benchmarks/sweep_threads.py [--samples 200] [--duration 1.0]

Runs the bundled damped-swing sweep (Latin hypercube of D, D1, α, γ) with its samples
cut to ``--samples`` and its record to ``--duration`` s, once with --workers 0 (the
baseline: batches one after another on one thread) and once per thread count, each into
a fresh directory, and checks the summaries are bitwise equal.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
import warp as wp

import warpcloth as wc


def timed(workers: int, samples: int, duration: float, root: Path) -> tuple[float, object]:
    sweep = wc.load_sweep("damped_swing_sweep", [f"sweep.random.samples={samples}", f"run.duration_s={duration}"])
    start = time.perf_counter()
    summary = wc.run_sweep(sweep, root / f"w{workers}", workers=workers, progress=False)
    return time.perf_counter() - start, summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--duration", type=float, default=1.0)
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, warp {wp.__version__}")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        timed(0, 4, 0.05, root / "warm")  # compile before timing
        base, reference = timed(0, args.samples, args.duration, root)
        print(f"workers 0 (baseline): {base:.2f} s")
        for workers in range(1, (os.cpu_count() or 1) + 1):
            wall, summary = timed(workers, args.samples, args.duration, root)
            same = all(
                np.array_equal(summary[c].to_numpy(), reference[c].to_numpy(), equal_nan=True)
                for c in reference.columns
                if reference[c].dtype != object
            )
            print(
                f"workers {workers} (threads): {wall:.2f} s, {base / wall:.2f}× the baseline; "
                f"summary bitwise equal: {same}"
            )


if __name__ == "__main__":
    main()
