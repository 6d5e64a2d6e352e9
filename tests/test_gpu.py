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
