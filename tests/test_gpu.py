"""GPU runs agree with the CPU (skipped where Warp sees no CUDA device, as in CI)."""

import numpy as np
import pytest
import warp as wp
from conftest import overrides

import warpcloth as wc

pytestmark = pytest.mark.skipif(not wp.is_cuda_available(), reason="no CUDA device")


def test_cuda_batch_matches_cpu():
    # Same float64 arithmetic; the CUDA compiler may contract a·b + c into FMAs, so
    # agreement is to rounding amplified over 0.3 s of a chaotic-free swing: 1e-9 m.
    scenes = [
        wc.load_scene("impulsive_rotation", overrides(run__duration_s=0.3, damping__gamma_per_s=g))
        for g in (0.0, 0.3, 3.0)
    ]
    cpu = wc.simulate(scenes, device="cpu")
    gpu = wc.simulate(scenes, device="cuda:0")
    np.testing.assert_allclose(gpu.frames, cpu.frames, rtol=0, atol=1e-9)


def test_cuda_sheets_match_cpu():
    # The woven sheet's fused kernel (kernels/sheet.py) on both devices: three 15 mm
    # squares of the scene's wool with masing bending and shear, the clamp turned about
    # the weft by the impulsive rotation's quartic, 0.05 s. The same float64 arithmetic up
    # to FMA contraction: round-off grown over 10 000 steps, 1e-9 m as for the strip.
    from warpcloth.scene import ShearMaterial, build_batch
    from warpcloth.sheet import (
        SheetBuilder,
        SheetClampMotion,
        SheetMaterialSI,
        SheetRecorder,
        SheetSolver,
        rectangle,
        simulate_sheets,
    )

    scene = wc.load_scene("impulsive_rotation", overrides(material__bending_law="masing", run__duration_s=0.05))
    strip = build_batch([scene]).model.strips[0]
    g, shear = ShearMaterial(
        "masing", 0.6, {"hysteresis_d1_gf_per_cm": 0.8, "hysteresis_alpha_per_deg": 0.6, "hysteresis_phi0_deg": 8.0}
    ).si()
    sheet = SheetMaterialSI(warp=strip.material, weft=strip.material, shear_rigidity=g, shear=shear)
    frames = {}
    for device in ("cpu", "cuda:0"):
        builder = SheetBuilder(rectangle(0.015, 0.015, 0.005, (0.005, 0.005)))
        for gamma in (0.0, 0.3, 3.0):
            builder.add_sheet(sheet, damping=gamma, clamp=SheetClampMotion(strip.clamp, centre=(0.0, 0.0028, 0.0)))
        model = builder.finalize(device=device)
        recorder = SheetRecorder(scene.output_interval, scene.output.probes_per_frame, scene.run.duration_s)
        frames[device] = simulate_sheets(
            model, model.control(), SheetSolver(model, scene.integrator.dt_s), recorder
        ).frames
    assert np.isfinite(frames["cpu"]).all()
    assert np.abs(frames["cpu"][-1] - frames["cpu"][0]).max() > 1e-3  # the sheets moved
    np.testing.assert_allclose(frames["cuda:0"], frames["cpu"], rtol=0, atol=1e-9)
