"""The marker model on dots whose surroundings differ from side to side, as on a real rig:
a dark dot on a strip's edge has bright fabric on one side and a darker backdrop on the
other. The reference is the dot's own centre, drawn analytically (8 × 8 sub-samples a
pixel), blurred by a lens and by motion symmetric about the frame's time, with sensor
noise: nothing here is measured by the code under test."""

import numpy as np
import pytest

from warpcloth.calibrate.motion_fit.verdict import judged_noise
from warpcloth.io.measured import TrackedShapes
from warpcloth.track.markers import _blobs, _follow, _outline, noise_sigma

SUB = 8
SIZE = 80
RADIUS_PX = 6.0
BACKDROP, FABRIC, DOT = 90.0, 170.0, 10.0


def dot_on_an_edge(centre, blur_px, rng):
    """A dot of RADIUS_PX on the near edge of a fabric band: the band (bright) covers from
    1 px right of the dot's centre to 9 px right; the backdrop left of it and beyond. Motion
    blur (a box of blur_px along (1, 2)/√5, centred) then a lens blur of 0.7 px, noise 1 DN."""
    import cv2

    yy, xx = (np.mgrid[0 : SIZE * SUB, 0 : SIZE * SUB] + 0.5) / SUB - 0.5
    direction = np.array([1.0, 2.0]) / np.sqrt(5.0)
    n = max(int(blur_px * SUB) | 1, 1)
    image = np.zeros_like(xx)
    for k in np.arange(n) - n // 2:  # symmetric offsets about the frame's time
        cx, cy = centre + direction * k / SUB
        scene = np.where((xx > cx + 1.0) & (xx < cx + 9.0), FABRIC, BACKDROP)
        image += np.where((xx - cx) ** 2 + (yy - cy) ** 2 < RADIUS_PX**2, DOT, scene)
    image = image.reshape(SIZE, SUB, SIZE, SUB).mean(axis=(1, 3)) / n
    return cv2.GaussianBlur(image, (0, 0), 0.7) + rng.normal(0.0, 1.0, image.shape)


@pytest.mark.parametrize("blur_px", [0.0, 3.0])
def test_a_dot_between_fabric_and_backdrop_is_centred_within_a_fiftieth_of_a_pixel(blur_px):
    rng = np.random.default_rng(7)
    errors, stated = [], []
    for _ in range(24):
        centre = 40.0 + rng.uniform(-0.5, 0.5, 2)
        image = dot_on_an_edge(centre, blur_px, rng)
        darkening = BACKDROP - image  # the background: the rig without the strip
        rough, shapes, _, _ = _blobs(darkening, 10.0, (20.0, 900.0))
        assert len(rough) == 1
        found = _outline(image, rough[0], shapes[0], noise_sigma(darkening), 2 * RADIUS_PX)
        assert found is not None
        errors.append(found[0] - centre)
        stated.append(found[1])
    errors, stated = np.array(errors), np.array(stated)
    # a centroid of the clipped darkening is pulled 0.42 px towards the backdrop here (the
    # issue's 0.45 px); the outline is not
    assert np.all(np.abs(errors.mean(axis=0)) <= 0.02), errors.mean(axis=0)
    assert np.all(np.sqrt(np.mean(errors**2, axis=0)) <= 0.03), errors
    # the stated σ covers: a normal error is within 2σ 95 % of the time (measured 92 and 100 %)
    assert np.mean(np.abs(errors) <= 2.0 * stated) >= 0.85, (errors, stated)


def test_a_slab_of_the_clamp_is_not_a_dot():
    import cv2

    rng = np.random.default_rng(3)
    image = np.full((SIZE, SIZE), BACKDROP)
    # a dark sliver of a dot's area, 2 px by 55 px (a clamp edge uncovered as it turns)
    image[30:32, 10:65] = DOT
    image = cv2.GaussianBlur(image, (0, 0), 0.7) + rng.normal(0.0, 1.0, image.shape)
    darkening = BACKDROP - image
    rough, shapes, _, _ = _blobs(darkening, 10.0, (20.0, 900.0))
    assert len(rough) == 1
    assert _outline(image, rough[0], shapes[0], noise_sigma(darkening), 2 * RADIUS_PX) is None


def test_markers_follow_their_own_motion_not_the_nearest_dot(tmp_path):
    s_mm = np.array([10.0, 20.0, 30.0])
    heading = np.array([[3.0, -10.0], [6.0, -19.5], [9.0, -29.0]])
    # a stray dark spot 9.7 mm from the first marker, nearer it than the second marker is
    stray = np.array([[3.2, -0.3]])
    dots = np.vstack([stray, heading + 0.2])
    nothing_hides = np.zeros(3, bool)
    order = _follow(dots, heading, 5.0, s_mm, "frame 4", tmp_path / "v.mp4", nothing_hides)
    assert order.tolist() == [1, 2, 3]
    with pytest.raises(Exception, match=r"frame 4 .*marker s = 30 mm lost: no dot within 5 mm"):
        _follow(dots[:3], heading, 5.0, s_mm, "frame 4 (t = 0.06 s)", tmp_path / "v.mp4", nothing_hides)
    # behind the clamp: hidden; the stray dot is no dot its neighbour along the strip allows
    order = _follow(dots[:3], heading, 5.0, s_mm, "frame 4", tmp_path / "v.mp4", np.array([False, False, True]))
    assert order.tolist() == [1, 2, -1]


def test_a_fit_of_tracked_shapes_is_judged_against_the_uncertainty_the_tracker_stated():
    n = 40
    shapes = TrackedShapes(
        np.repeat(np.arange(n), 2), np.repeat(np.arange(n) / 60, 2), np.tile([0.01, 0.02], n),
        np.zeros(2 * n), np.zeros(2 * n), np.full(2 * n, 3e-6),
    )  # fmt: skip
    noise, source = judged_noise(shapes, None, np.zeros(4 * n))
    assert noise == pytest.approx(3e-6) and "u_mm" in source
    # without the tracker's u: the residuals' 4th differences, not the motion's
    plain = TrackedShapes(shapes.frame, shapes.t, shapes.s, np.sin(40 * shapes.t), shapes.y)
    residual = np.random.default_rng(0).normal(0.0, 1e-5, 4 * n)
    noise, source = judged_noise(plain, None, residual)
    assert noise == pytest.approx(1e-5, rel=0.35) and "residuals" in source
