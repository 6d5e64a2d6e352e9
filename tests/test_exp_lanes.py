"""The CPU force pass's groups of hinges (kernels/exp_lanes.py, kernels/forces.py): the
exponentials of a group in one libmvec call, against glibc's scalar ``exp`` of each.

One hinge at a time (``WARPCLOTH_EXP_LANES=1``) is bitwise the force pass of before the
groups (tests/test_golden.py runs it so). In groups, libmvec's exponentials are within its
promised 4 ulp of the exact value where the scalar ``exp`` is within 1, so a strip moves by
rounding: on the golden cases (the paper's law, 0.5–4.3 s simulated) frames moved by at
most 2.2e-12 of their largest value and each probe by at most 4.4e-10 of its own largest
(2026-12-07, this machine). The tolerances below are about 4.5 times those.
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import warp as wp
from warpcloth.kernels import exp_lanes, laws, precision

import warpcloth as wc
from warpcloth.errors import EnvironmentSettingError
from warpcloth.scene import to_si
from warpcloth.strip.state import allocate_reversal_memory

sys.path.insert(0, str(Path(__file__).parent / "golden"))
from make_goldens import CASES, scene_outputs  # noqa: E402

FRAMES_TOLERANCE = 1e-11
"""Largest change of a golden case's frames in groups, relative to their largest value."""
PROBE_TOLERANCE = 2e-9
"""Largest change of each golden probe in groups, relative to its own largest value."""

needs_libmvec = pytest.mark.skipif(
    not exp_lanes.vector_exp_available(),
    reason="no libmvec, AVX2 and FMA here (Linux x86-64 with glibc): every hinge is taken alone",
)


@pytest.fixture
def lanes(monkeypatch):
    def set_width(width):
        monkeypatch.setenv(exp_lanes.ENVIRONMENT, str(width))

    return set_width


@needs_libmvec
@pytest.mark.parametrize("width", [4, 8])
def test_libmvecs_exponentials_are_within_its_4_ulp(width):
    # against exp in x87 extended precision, rounded once: what "4 ulp" is measured from
    exp_of_lanes = exp_lanes.build(wp.float64, width)
    Lanes = wp.types.vector(width, dtype=wp.float64)

    @wp.kernel(module="unique", enable_backward=False)
    def lanes_of(x: wp.array(dtype=Lanes), out: wp.array(dtype=Lanes)):
        i = wp.tid()
        out[i] = exp_of_lanes(x[i])

    rng = np.random.default_rng(41)
    # what the paper's law asks for (−α|ΔK| ≤ 0, mostly small), and the whole range
    x = np.concatenate([-rng.exponential(1e-3, 2**14), rng.uniform(-745.0, 709.0, 2**14), [0.0] * width])
    x = x[: len(x) // width * width]
    out = wp.zeros(len(x) // width, dtype=Lanes, device="cpu")
    wp.launch(
        lanes_of, len(x) // width, inputs=[wp.array(x.reshape(-1, width), dtype=Lanes, device="cpu"), out], device="cpu"
    )
    got = out.numpy().reshape(-1)
    # libmvec was called: glibc's scalar exp rounds about half of these otherwise
    assert np.any(got != np.array([math.exp(v) for v in x]))
    exact = np.exp(x.astype(np.longdouble))
    if np.finfo(np.longdouble).nmant < 60:
        pytest.skip("no extended precision here to measure ulps against")
    normal = exact > np.finfo(np.float64).tiny
    ulps = np.abs(got[normal] - exact[normal]) / np.spacing(exact[normal].astype(np.float64))
    assert ulps.max() <= 4.0, f"libmvec's {width}-wide exp is {ulps.max():.1f} ulp off"
    assert np.all(got[x == 0.0] == 1.0)


def test_follow_is_its_two_parts_bitwise_for_every_law():
    # kernels/law.py: follow = decay(m, exp(x)) of (m, x) = follow_before_decay(...), the
    # split the force pass's groups take, on a wandering curvature path with many reversals
    law = laws.build(wp.float64)

    @wp.kernel(module="unique", enable_backward=False)
    def both(
        path: wp.array(dtype=wp.float64),
        parameters: wp.array(dtype=law.Parameters),
        history_whole: law.History,
        history_split: law.History,
        whole: wp.array2d(dtype=law.Memory),
        split: wp.array2d(dtype=law.Memory),
    ):
        s = wp.tid()
        p = parameters[s]
        a = law.fresh_memory(path[0], p, history_whole, 0, s)
        b = law.fresh_memory(path[0], p, history_split, 0, s)
        for n in range(path.shape[0]):
            a = law.follow(path[n], a, p, history_whole, 0, s)
            before, exponent = law.follow_before_decay(path[n], b, p, history_split, 0, s)
            b = law.decay(before, wp.exp(exponent), p)
            whole[n, s] = a
            split[n, s] = b

    names = list(laws.BENDING_LAWS)
    packed = [
        to_si(wc.load_scene("damped_swing", {"material.bending_law": n}).material).bending_parameters() for n in names
    ]
    path = np.cumsum(np.random.default_rng(0).normal(0.0, 0.6, 4000))  # 1/m
    vec2 = precision(wp.float64).vec2
    histories = [allocate_reversal_memory(law.History, 4000, 1, len(names), vec2, "cpu") for _ in range(2)]
    whole = wp.zeros((len(path), len(names)), dtype=law.Memory, device="cpu")
    split = wp.zeros((len(path), len(names)), dtype=law.Memory, device="cpu")
    wp.launch(
        both,
        len(names),
        inputs=[
            wp.array(path, dtype=wp.float64, device="cpu"),
            wp.array(np.array(packed), dtype=law.Parameters, device="cpu"),
            *histories,
            whole,
            split,
        ],
        device="cpu",
    )
    for j, name in enumerate(names):
        assert whole.numpy()[:, j].tobytes() == split.numpy()[:, j].tobytes(), name


@needs_libmvec
@pytest.mark.parametrize("width", [4, 8])
@pytest.mark.parametrize("case", list(CASES))
def test_golden_cases_in_groups_are_within_rounding_of_one_at_a_time(case, width, lanes):
    expected = np.load(Path(__file__).parent / "golden" / f"{case}.npz")  # one hinge at a time
    lanes(width)
    actual = scene_outputs(case)
    if case == "float32":  # float32 takes one hinge at a time on every device
        assert actual["frames"].tobytes() == expected["frames"].tobytes()
        return
    if case != "forward_euler":  # its 0.015 s at 2e-7 s: exponents so small both round them alike
        assert actual["frames"].tobytes() != expected["frames"].tobytes()  # the groups did run
    frames, golden = actual["frames"], expected["frames"]
    assert np.array_equal(np.isnan(frames), np.isnan(golden))  # forward Euler's divergence, recorded
    largest = np.nanmax(np.abs(golden))
    assert np.nanmax(np.abs(frames - golden)) <= FRAMES_TOLERANCE * largest
    probes, golden = actual["probes"], expected["probes"]
    assert np.array_equal(np.isnan(probes), np.isnan(golden))
    own_largest = np.nanmax(np.abs(golden), axis=0)
    assert np.all(np.nanmax(np.abs(probes - golden), axis=0) <= PROBE_TOLERANCE * own_largest)


@needs_libmvec
def test_laws_without_a_decay_of_their_own_are_bitwise_in_groups(lanes):
    # masing, Dahl, the frictional couple and masing_growing take their hinges one at a
    # time in any group width; the paper's law without hysteresis (D1 = 0) decays nothing,
    # and libmvec's e^0 is 1: all bitwise, in one batch with a hysteretic paper strip
    names = [n for n in laws.BENDING_LAWS if not laws.build(wp.float64).decays[laws.LAWS.index(laws.bending_law(n))]]
    assert names and "tagawa2003" not in names
    short = {"release.settle_time_s": 0.2, "run.duration_s": 0.4}
    scenes = [wc.load_scene("damped_swing", {"material.bending_law": n, **short}) for n in names]
    scenes.append(wc.load_scene("damped_swing_paper", {"material.hysteresis_d1_gf_cm_per_cm": 0.0, **short}))
    scenes.append(wc.load_scene("damped_swing_paper", short))
    frames = {}
    for width in (1, 4):
        lanes(width)
        frames[width] = wc.simulate(scenes).frames
    for j in range(len(scenes) - 1):
        assert frames[4][:, j].tobytes() == frames[1][:, j].tobytes(), scenes[j].material.bending_law
    hysteretic = np.abs(frames[4][:, -1] - frames[1][:, -1]).max()
    assert 0 < hysteretic <= FRAMES_TOLERANCE * np.abs(frames[1][:, -1]).max()


@needs_libmvec
@pytest.mark.parametrize("spacing_mm", [2.5, 4.0, 5.0, 10.0, 20.0])
def test_strips_of_any_hinge_count_in_groups(spacing_mm, lanes):
    # 40, 25, 20, 10 and 5 free segments: whole groups of 4 and 8, and groups left over
    scene = wc.load_scene("impulsive_rotation_paper", {"strip.spacing_mm": spacing_mm, "run.duration_s": 0.3})
    frames = {}
    for width in (1, 4, 8):
        lanes(width)
        frames[width] = wc.simulate(scene).frames
    largest = np.abs(frames[1]).max()
    for width in (4, 8):
        assert not np.array_equal(frames[width], frames[1]), width  # the groups did run
        assert np.abs(frames[width] - frames[1]).max() <= FRAMES_TOLERANCE * largest, width


@pytest.mark.parametrize("value", ["3", "x", "0", "-4"])
def test_an_unknown_group_width_is_refused_naming_the_variable(value, lanes, tmp_path):
    from conftest import run_cli

    lanes(value)
    refusal = rf"{exp_lanes.ENVIRONMENT}: is '{value}'; it must be auto or one of 1, 4, 8"
    with pytest.raises(EnvironmentSettingError, match=refusal):
        wc.simulate(wc.load_scene("damped_swing", {"run.duration_s": 0.01}))
    # the command line says it in one line before the command starts
    for command in (["run", "damped_swing"], ["sweep", "damped_swing_sweep", "--set", "sweep.random.samples=2"]):
        done = run_cli(*command, "--out", tmp_path / command[0])
        assert done.returncode == 2 and done.stdout == "", done.stdout
        assert done.stderr == (
            f"warpcloth {command[0]}: error in environment variable: {exp_lanes.ENVIRONMENT}: is {value!r}; "
            "it must be auto or one of 1, 4, 8\n"
        )
        assert not (tmp_path / command[0]).exists()


@pytest.mark.parametrize("value", ["", " ", "auto"])
def test_an_empty_setting_is_auto(value, lanes):
    lanes(value)
    assert exp_lanes.requested_width() is None
    assert exp_lanes.lane_width(wp.float64, True) == (4 if exp_lanes.vector_exp_available() else 1)


def test_a_gpu_and_float32_take_one_hinge_at_a_time(lanes):
    lanes(8 if exp_lanes.libmvec_loaded() else 1)
    assert exp_lanes.lane_width(wp.float64, False) == 1
    assert exp_lanes.lane_width(wp.float32, True) == 1
    lanes(3)  # but an unknown width is refused there too
    for scalar, cpu in ((wp.float64, False), (wp.float32, True)):
        with pytest.raises(EnvironmentSettingError, match=exp_lanes.ENVIRONMENT):
            exp_lanes.lane_width(scalar, cpu)


def test_an_unknown_group_width_is_refused_before_a_sheet_starts(lanes):
    lanes("two")
    with pytest.raises(EnvironmentSettingError, match=exp_lanes.ENVIRONMENT):
        wc.simulate(wc.load_scene("shear_swing", {"run.duration_s": 0.01}))
