"""A batch is B independent strips: per-strip results equal single runs, bit for bit."""

import numpy as np
import pytest
from conftest import overrides

import warpcloth as wc

VARIANTS = [
    dict(),
    dict(material__hysteresis_d1_gf_cm_per_cm=0.08, damping__gamma_per_s=1.0),
    dict(
        material__bending_rigidity_gf_cm2_per_cm=0.3,
        clamp__rotation_centre_dy_mm=0.0,
        material__density_g_per_cm2=0.03,
        strip__width_mm=30.0,
    ),
    dict(
        clamp__segments__1__theta_coefficients_si=[0.2, 10.0],
        clamp__segments__1__t_end_s=0.15,
        material__tensile_gf_per_cm=[3000.0, 0.0, 1e5, 2e7],
    ),
]


def scene(**fields):
    return wc.load_scene("impulsive_rotation", overrides(run__duration_s=0.25, **fields))


@pytest.fixture(scope="module")
def batch():
    return wc.simulate([scene(**v) for v in VARIANTS])


def test_batch_equals_single_runs(batch):
    # Each strip runs the same instructions on the same numbers whether alone or in a
    # batch, so the comparison is exact (no tolerance).
    for i, fields in enumerate(VARIANTS):
        single = wc.simulate(scene(**fields))
        np.testing.assert_array_equal(batch.probes[:, :, i], single.probes[:, :, 0])
        np.testing.assert_array_equal(batch.frames[:, i], single.frames[:, 0])


def test_variants_really_differ(batch):
    tips = batch.probe("tip_x")
    for i in range(1, len(VARIANTS)):
        assert np.max(np.abs(tips[:, i] - tips[:, 0])) > 1e-4


def test_strips_do_not_interact(batch):
    # Changing every per-strip parameter of strip 3 leaves strips 0-2 untouched.
    changed = VARIANTS[:3] + [
        dict(material__hysteresis_d1_gf_cm_per_cm=0.2, damping__gamma_per_s=5.0, clamp__rotation_centre_dx_mm=3.0)
    ]
    other = wc.simulate([scene(**v) for v in changed])
    np.testing.assert_array_equal(other.probes[:, :, :3], batch.probes[:, :, :3])
    assert np.max(np.abs(other.probe("tip_x", 3) - batch.probe("tip_x", 3))) > 1e-4


def test_one_diverging_strip_does_not_stop_the_others():
    # Forward Euler at dt = 2e-5 s: the default material's stiffest mode (ω dt ≈ 0.8)
    # blows up; a soft, heavily damped variant (ω ≈ 4e3 1/s, γ dt = 8e-3 > ω² dt / 2)
    # is stable and must run to the end.
    def hanging(**fields):
        return wc.load_scene(
            "damped_swing",
            overrides(
                release__enabled=False,
                integrator__dt_s=2e-5,
                integrator__scheme="forward",
                run__duration_s=0.3,
                **fields,
            ),
        )

    scenes = [
        hanging(damping__gamma_per_s=0.0),
        hanging(damping__gamma_per_s=400.0, material__tensile_gf_per_cm=[20.0, 0.0, 0.0, 0.0]),
    ]
    result = wc.simulate(scenes, on_divergence="record")
    assert [d.strip for d in result.diverged] == [0]
    diverged_at = result.diverged[0].time_s
    assert np.all(np.isnan(result.probe("tip_x", 0)[result.t > diverged_at]))
    assert np.all(np.isfinite(result.probe("tip_x", 1)))


def test_batch_level_fields_must_agree():
    with pytest.raises(wc.SceneError, match="integrator.dt_s: differs between variant 0"):
        wc.simulate([scene(), scene(integrator__dt_s=2e-6)])


@pytest.mark.slow
def test_a_batch_on_threads_is_the_batch_on_one_thread_bit_for_bit():
    # one launch per thread over contiguous ranges of strips (Warp's CPU launch runs on one
    # thread and releases the GIL): the same arithmetic per strip, a diverging strip included
    # (ranges of at least STRIPS_PER_THREAD = 8 strips: 25 strips make up to 3)
    scenes = [
        wc.load_scene(
            "damped_swing",
            overrides(
                run__duration_s=0.2,
                release__settle_time_s=0.1,
                damping__gamma_per_s=g,
                material__hysteresis_d1_gf_cm_per_cm=d1,
            ),
        )
        for g in (0.1, 0.5, 0.9, 1.3, 1.7, 2.1)
        for d1 in (0.0, 0.02, 0.04, 0.06)
    ]
    scenes.insert(
        10,
        wc.load_scene(
            "damped_swing",
            overrides(
                run__duration_s=0.2, release__settle_time_s=0.1, material__tensile_gf_per_cm=[0.5, 0.0, 0.0, 0.0]
            ),
        ),
    )
    one = wc.simulate(scenes, threads=1, on_divergence="record")
    assert [d.strip for d in one.diverged] == [10]
    for threads in (2, 3, 7):
        many = wc.simulate(scenes, threads=threads, on_divergence="record")
        assert np.array_equal(many.probes, one.probes, equal_nan=True)
        assert np.array_equal(many.frames, one.frames, equal_nan=True)
        assert many.diverged == one.diverged
    with pytest.raises(wc.ArgumentError, match="threads: must be at least 1, got 0"):  # the argument named (issue 37)
        wc.simulate(scenes[:1], threads=0)
