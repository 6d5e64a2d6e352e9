"""The GPU checks and throughput tables in one script, for a machine with an NVIDIA GPU
(issue 11, item 6; run by hand, under 5 minutes):

    python benchmarks/gpu.py [--device cuda:0] [--quick]

1. Agreement: the GPU's float64 trajectories against the CPU's (tests/test_gpu.py, run by
   pytest), and each scheme (semi_implicit, imex) and bending law on both devices.
2. Throughput: strip-steps/s and node-steps/s of the damped swing for B = 1e3, 1e4, 1e5
   strips, float64 and float32, both schemes, against the CPU at B = 1e3 measured in the
   same run; the issue's target is ≥ 2e10 node-steps/s in float64 at B = 1e4–1e5.
3. Paper-faithful work: 10 000 strip-seconds of the damped swing at dt = 1e-7 s (the
   paper took 210 s for one), timed on a short record and scaled, and stated as such.
4. The woven sheet (issue 23): node-steps/s of B = 1e3, 1e4 sheets of the 50 mm square at
   5 mm (benchmarks/sheet_throughput.py), masing bending and shear, float64 and float32,
   against the CPU's B = 32 on all its cores measured in the same run (one GPU thread
   advances one sheet, as a CPU task does).
5. The bundled sweep (issue 41): `damped_swing_sweep` (paper law, dt "auto", 1.3 s hold
   and 3 s swing) at 10 000 variants through ``run_sweep`` as `warpcloth sweep` runs it,
   its summary's probes kept (the default), against 200 of its variants on every CPU core
   in the same run: wall, variants/s, node-steps/s, the bytes written, the ratio.

Kernels are compiled (and cached) before timing. Without a CUDA device it says so and
exits 2 (nothing to measure); ``--device cpu --sheet-only`` and ``--device cpu
--sweep-only`` run section 4's or 5's CPU rows alone (smoke runs of the script on any
machine).
"""

from __future__ import annotations

import argparse
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import warp as wp
from sheet_throughput import sheet_rate

import warpcloth as wc
from warpcloth.core.runner import available_cores
from warpcloth.strip.model import init_warp_quietly

ROOT = Path(__file__).resolve().parents[1]


def swing(scheme: str, precision: str, duration: float, dt: float | None = None, law: str = "tagawa2003") -> wc.Scene:
    fields = {
        "run.duration_s": duration,
        "integrator.scheme": scheme,
        "integrator.precision": precision,
        "release.move_time_s": 0.1,
        "release.settle_time_s": 0.0,
        "material.bending_law": law,
    }
    if dt is not None:
        fields["integrator.dt_s"] = dt
    elif scheme == "imex":
        fields["integrator.dt_s"] = 2e-4
    return wc.load_scene("damped_swing", fields)


def rate(scene: wc.Scene, batch: int, device: str) -> tuple[float, float, float]:
    """Strip-steps/s, node-steps/s and wall (s) of ``batch`` copies, after a warm-up run."""
    wc.simulate([scene], device=device, keep_frames=False)
    started = time.perf_counter()
    result = wc.simulate([scene] * batch, device=device, keep_frames=False)
    wall = time.perf_counter() - started
    return result.strip_steps / wall, result.strip_steps * scene.n_nodes / wall, wall


def agreement(device: str) -> None:
    print("\n1. agreement, GPU against CPU (float64)")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(ROOT / "tests" / "test_gpu.py")],
        capture_output=True,
        text=True,
    )
    print("   tests/test_gpu.py:", done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr[-300:])
    for scheme in ("semi_implicit", "imex"):
        for law in ("tagawa2003", "dahl", "frictional_couple"):
            scene = swing(scheme, "float64", 0.3, law=law)
            cpu, gpu = (wc.simulate([scene] * 4, device=d) for d in ("cpu", device))
            gap = np.nanmax(np.abs(gpu.frames - cpu.frames))
            print(f"   {scheme:13s} {law:17s} largest |Δx| over 0.3 s: {gap:.2e} m")


def throughput(device: str, sizes: list[int], duration: float) -> None:
    print(f"\n2. throughput, damped swing, {duration} s simulated per run")
    header = ("scheme", "precision", "B", "strip-steps/s", "node-steps/s", "vs CPU B=1e3")
    print("   {:13s} {:9s} {:>7} {:>14} {:>13} {:>13}".format(*header))
    for scheme in ("semi_implicit", "imex"):
        for precision in ("float64", "float32"):
            scene = swing(scheme, precision, duration)
            cpu, _, _ = rate(scene, 1000, "cpu")
            print(f"   {scheme:13s} {precision:9s} {'cpu 1e3':>7} {cpu:14.3e} {cpu * scene.n_nodes:13.3e} {1.0:12.2f}x")
            for b in sizes:
                strips, nodes, _ = rate(scene, b, device)
                print(f"   {scheme:13s} {precision:9s} {b:>7} {strips:14.3e} {nodes:13.3e} {strips / cpu:12.2f}x")


def paper_faithful(device: str, batch: int) -> None:
    print("\n3. paper-faithful work: dt = 1e-7 s, float64, semi_implicit")
    duration = 0.01
    scene = swing("semi_implicit", "float64", duration, dt=1e-7)
    strips, _, wall = rate(scene, batch, device)
    strip_seconds = batch * duration
    print(
        f"   {batch} strips × {duration} s in {wall:.2f} s: 10 000 strip-seconds would take "
        f"{wall * 1e4 / strip_seconds:.0f} s (scaled from this run; the paper: 210 s for one)"
    )


def sheets(device: str, sizes: list[int], duration: float) -> None:
    """Section 4: the sheet's node-steps/s at each of ``sizes`` on ``device`` against the CPU's
    32 sheets on all its cores (only the CPU rows when ``device`` is the CPU)."""
    print(f"\n4. the woven sheet, 50 mm square at 5 mm, masing, {duration} s simulated per run")
    print("   {:9s} {:>9} {:>13} {:>13}".format("precision", "B", "node-steps/s", "vs CPU B=32"))
    for precision in ("float64", "float32"):
        cpu = sheet_rate("masing", precision, 32, duration, available_cores())
        print(f"   {precision:9s} {'cpu 32':>9} {cpu:13.3e} {1.0:12.2f}x")
        if device == "cpu":
            continue
        for b in sizes:
            rate = sheet_rate("masing", precision, b, duration, 1, device)
            print(f"   {precision:9s} {b:>9} {rate:13.3e} {rate / cpu:12.2f}x")


ISSUE_41_SWEEP = ("material.bending_law=tagawa2003", "integrator.dt_s=auto", "run.duration_s=3.0")
"""The bundled sweep as issue 41 times it: the paper's law, the step dt "auto" chooses
(semi-implicit, within 0.2 % of dt = 1e-7 s), its 1.3 s hold and a 3 s swing."""


def sweep_rate(device: str, samples: int) -> tuple[float, int]:
    """Variants/s and bytes written of ``samples`` variants of the bundled sweep run as
    `warpcloth sweep` runs them (a fresh directory, kernels warmed by it): on the CPU in its
    default batches on every core, on a GPU as one batch (a GPU needs thousands of strips
    at once; the batch's step is then its stiffest variant's)."""
    sweep = wc.load_sweep("damped_swing_sweep", [*ISSUE_41_SWEEP, f"sweep.random.samples={samples}"])
    on_gpu = device != "cpu"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "sweep"
        started = time.perf_counter()
        wc.run_sweep(sweep, out, device=device, workers=1 if on_gpu else None, max_batch=samples if on_gpu else None)
        wall = time.perf_counter() - started
        written = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    return samples / wall, written


def sweeps(device: str, samples: int) -> None:
    """Section 5: the bundled sweep's variants/s on ``device`` against 200 of its variants on
    every CPU core (only the CPU row when ``device`` is the CPU)."""
    print("\n5. the bundled sweep (damped_swing_sweep, paper law, dt auto, 3 s swing), summary probes kept")
    print("   {:>14} {:>9} {:>11} {:>9} {:>12}".format("device", "variants", "variants/s", "vs CPU", "kB/variant"))
    cpu, cpu_bytes = sweep_rate("cpu", 200)
    print(f"   {'cpu (all)':>14} {200:>9} {cpu:11.1f} {1.0:8.2f}x {cpu_bytes / 200 / 1e3:12.0f}")
    if device != "cpu":
        gpu, gpu_bytes = sweep_rate(device, samples)
        print(f"   {device:>14} {samples:>9} {gpu:11.1f} {gpu / cpu:8.2f}x {gpu_bytes / samples / 1e3:12.0f}")
    best = cpu if device == "cpu" else max(cpu, gpu)
    print(f"   10 000 variants: {1e4 / best:.0f} s at the best rate here (the paper: 210 s for one)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="cuda:0")
    parser.add_argument("--quick", action="store_true", help="B up to 1e4 and shorter records")
    parser.add_argument("--sheet-only", action="store_true", help="section 4 alone (with --device cpu: its CPU rows)")
    parser.add_argument("--sweep-only", action="store_true", help="section 5 alone (with --device cpu: its CPU row)")
    args = parser.parse_args()
    init_warp_quietly()
    sheet_sizes = [1000] if args.quick else [1000, 10000]
    if args.device != "cpu" and not wp.is_cuda_available():
        print("no CUDA device here: run this on a machine with an NVIDIA GPU", file=sys.stderr)
        return 2
    if args.sheet_only:
        sheets(args.device, sheet_sizes, 0.005)
        return 0
    if args.sweep_only:
        sweeps(args.device, 2000 if args.quick else 10000)
        return 0
    if args.device == "cpu":
        print(
            "sections 1-3 compare a GPU with the CPU: give --device cuda:N, --sheet-only or --sweep-only",
            file=sys.stderr,
        )
        return 2
    print(f"{platform.node()}: {wp.get_device(args.device).name}, Warp {wp.__version__}")
    agreement(args.device)
    throughput(args.device, [1000, 10000] if args.quick else [1000, 10000, 100000], 0.02 if args.quick else 0.05)
    paper_faithful(args.device, 10000 if args.quick else 100000)
    sheets(args.device, sheet_sizes, 0.005)
    sweeps(args.device, 2000 if args.quick else 10000)
    return 0


if __name__ == "__main__":
    sys.exit(main())
