"""Kinematic clamp: θ(t) evaluation and the rigid rotation of the clamp nodes."""

import numpy as np
import pytest
from conftest import overrides

import warpcloth as wc
from warpcloth.scene import build_batch
from warpcloth.scene.clamp_motion import clamp_pieces, evaluate


def test_piecewise_quartic_then_line_matches_host_evaluation():
    scene = wc.load_scene("impulsive_rotation", overrides(run__duration_s=0.2))
    result = wc.simulate(scene)
    expected = evaluate(*clamp_pieces(scene.clamp), result.t)
    # float64 Horner evaluation of the same polynomial: agreement to rounding.
    np.testing.assert_allclose(result.probe("clamp_angle", 0), expected, rtol=0, atol=1e-13)
    assert expected[-1] == pytest.approx(1.32)  # held after the last segment


def test_clamp_nodes_rotate_rigidly_about_the_rotation_centre():
    scene = wc.load_scene("impulsive_rotation", overrides(run__duration_s=0.2))
    result = wc.simulate(scene)
    centre = build_batch([scene]).control.rotation_centre[0]
    theta = evaluate(*clamp_pieces(scene.clamp), result.frame_times)
    clamp = result.frames[:, 0, : scene.n_clamped]
    rest = clamp[0]
    for frame, angle in zip(clamp, theta, strict=True):
        c, s = np.cos(angle), np.sin(angle)
        expected = centre + (rest - centre) @ np.array([[c, s], [-s, c]])
        np.testing.assert_allclose(frame, expected, atol=1e-15)


def test_a_rotation_centre_does_nothing_to_a_clamp_that_does_not_turn():
    # θ = 0 throughout: the clamp stays on its rest positions whatever the centre, bit
    # for bit (centre + (X − centre) used to move it by rounding, and the run with it).
    runs = [
        wc.simulate(
            wc.load_scene(
                "damped_swing",
                overrides(
                    run__duration_s=0.2,
                    release__settle_time_s=0.1,
                    clamp__rotation_centre_dx_mm=dx,
                    clamp__rotation_centre_dy_mm=dy,
                ),
            )
        )
        for dx, dy in ((0.0, 0.0), (3.0, 7.3), (-11.0, 2.8))
    ]
    rest = build_batch([wc.load_scene("damped_swing")]).model.rest_positions
    for run in runs:
        assert run.frames.tobytes() == runs[0].frames.tobytes()
        assert run.probes.tobytes() == runs[0].probes.tobytes()
    assert runs[0].frames[:, 0, :5].tobytes() == np.broadcast_to(rest[:5], runs[0].frames[:, 0, :5].shape).tobytes()


def test_sampled_table_linear_and_cubic():
    t = [0.0, 0.02, 0.05, 0.08, 0.1]
    theta = [0.0, 0.05, 0.3, 0.6, 0.7]
    for interpolation in ("linear", "cubic"):
        scene = wc.load_scene(
            "impulsive_rotation",
            overrides(
                clamp__motion="table",
                clamp__table_t_s=t,
                clamp__table_theta_rad=theta,
                clamp__interpolation=interpolation,
                run__duration_s=0.15,
                output__probes_per_frame=100,
            ),
        )
        start, end, coefficients = clamp_pieces(scene.clamp)
        # passes through every sample, and the kernel evaluates the same pieces
        np.testing.assert_allclose(evaluate(start, end, coefficients, np.array(t)), theta, atol=1e-14)
        result = wc.simulate(scene)
        np.testing.assert_allclose(
            result.probe("clamp_angle", 0), evaluate(start, end, coefficients, result.t), atol=1e-13
        )
    # natural cubic spline: θ' and θ'' continuous at the knots, θ'' = 0 at the ends
    d1 = coefficients[:, 1] + 2 * coefficients[:, 2] * (end - start) + 3 * coefficients[:, 3] * (end - start) ** 2
    d2 = 2 * coefficients[:, 2] + 6 * coefficients[:, 3] * (end - start)
    np.testing.assert_allclose(d1[:-1], coefficients[1:, 1], rtol=1e-10)
    np.testing.assert_allclose(d2[:-1], 2 * coefficients[1:, 2], rtol=1e-9, atol=1e-9)
    assert coefficients[0, 2] == 0.0 and d2[-1] == pytest.approx(0.0, abs=1e-9)
