"""The fabric's set (docs/model.md §5.4): a natural curvature K_rest(s) every bending law
bends from. Exact references: without gravity the strip rests as the arc of its natural
curvature; with gravity, clamped horizontally, it takes the heavy elastica with natural
curvature (shooting, warpcloth.calibrate.references.heavy_elastica); every law started on
its rest arc stays there; the energy budget closes with a set and a grip."""

import math

import numpy as np
import pytest
from conftest import overrides
from test_elastica import LENGTH_M, horizontal_scene
from warpcloth.kernels import BENDING_LAWS

import warpcloth as wc
from warpcloth.calibrate.references import heavy_elastica
from warpcloth.scene import to_si


def circumcurvature(a, b, c):
    """Signed curvature of the circle through three points (counter-clockwise +)."""
    u, v = b - a, c - b
    cross = u[0] * v[1] - u[1] * v[0]
    return 2 * cross / (np.linalg.norm(u) * np.linalg.norm(v) * np.linalg.norm(c - a))


def exact_hanging_shape(curvature, s):
    """Positions (from the clamp edge) of an unloaded strip hanging from the clamp with
    natural curvature K(s): θ(s) = ∫K, the tangent (sin θ, −cos θ), by the trapezoid rule
    on a fine grid."""
    fine = np.linspace(0.0, s[-1], 20001)
    k = curvature(fine)
    theta = np.concatenate([[0.0], np.cumsum(np.diff(fine) * (k[1:] + k[:-1]) / 2)])
    x = np.concatenate([[0.0], np.cumsum(np.diff(fine) * (np.sin(theta[1:]) + np.sin(theta[:-1])) / 2)])
    y = np.concatenate([[0.0], np.cumsum(np.diff(fine) * -(np.cos(theta[1:]) + np.cos(theta[:-1])) / 2)])
    return np.column_stack([np.interp(s, fine, x), np.interp(s, fine, y)])


def test_the_reference_with_natural_curvature_has_its_limits():
    # κ → 0: the strip keeps its natural arc, reach sin q, lift 1 − cos q, tip angle −q
    arc = heavy_elastica(1e-6, natural_curvature=1.0)
    assert arc["tip_reach"] == pytest.approx(math.sin(1.0), rel=1e-6)
    assert arc["tip_drop"] == pytest.approx(-(1 - math.cos(1.0)), rel=1e-5)
    assert arc["tip_angle"] == pytest.approx(-1.0, rel=1e-5)
    # a constant q does not change the equation, only the free end: q = 0 is the old shape
    assert heavy_elastica(8.0, natural_curvature=0.0) == heavy_elastica(8.0)
    # a profile given as a function agrees with the same constant given as a number
    assert heavy_elastica(8.0, natural_curvature=lambda s: 0.5)["tip_drop"] == pytest.approx(
        heavy_elastica(8.0, natural_curvature=0.5)["tip_drop"], rel=1e-12
    )


UNLOADED = {
    "constant +": (["strip.rest_curvature_per_cm=0.1"], lambda s: np.full_like(s, 10.0)),
    "constant −": (["strip.rest_curvature_per_cm=-0.25"], lambda s: np.full_like(s, -25.0)),
    "table": (
        ["strip.rest_curvature_table_s_mm=[0.0, 40.0, 100.0]", "strip.rest_curvature_table_per_cm=[0.2, -0.1, 0.05]"],
        lambda s: np.interp(s, [0.0, 0.04, 0.1], [20.0, -10.0, 5.0]),
    ),
}


@pytest.fixture(scope="module")
def unloaded():
    # No gravity, linear bending, damping critical for the first cantilever mode: the
    # strip starts straight and curls into its natural shape.
    base = overrides(
        run__gravity_m_per_s2=0.0,
        material__hysteresis_d1_gf_cm_per_cm=0.0,
        release__enabled=False,
        run__duration_s=10.0,
        damping__gamma_per_s=4.9,
    )
    scenes = [wc.load_scene("damped_swing", base + extra) for extra, _ in UNLOADED.values()]
    return scenes, wc.simulate(scenes)


def test_without_gravity_a_constant_set_rests_as_its_circular_arc(unloaded):
    # Every hinge at K_rest: measured to 2e-10 relative (what the damping leaves after 10 s);
    # the nodes then lie on the circle of radius 1/K_rest through the clamp edge, and the
    # shape is the exact arc of that curvature but for the chain's chords being shorter
    # than their arcs by (Kh)²/24: measured 9.0e-5 L (K h = 0.05) and 5.0e-4 L (0.125),
    # below that deficit (1.0e-4 and 6.5e-4).
    scenes, result = unloaded
    for j, ((_, curvature), scene) in enumerate(zip(UNLOADED.values(), scenes, strict=True)):
        if scene.strip.rest_curvature_table_per_cm:
            continue
        nodes = result.frames[-1, j]
        nc = scene.n_clamped
        k_rest = curvature(np.zeros(1))[0]
        free = [circumcurvature(nodes[i - 1], nodes[i], nodes[i + 1]) for i in range(nc, len(nodes) - 1)]
        assert np.allclose(free, k_rest, rtol=1e-7, atol=0)
        # the clamp-edge hinge bends the half segment below the clamp: twice the chain's turn
        edge = 2 * circumcurvature(nodes[nc - 2], nodes[nc - 1], nodes[nc])
        assert edge == pytest.approx(k_rest, rel=1e-7)
        s = np.arange(len(nodes) - nc + 1) * scene.spacing
        exact = exact_hanging_shape(curvature, s)
        error = np.abs(nodes[nc - 1 :] - nodes[nc - 1] - exact).max() / LENGTH_M
        deficit = (k_rest * scene.spacing) ** 2 / 24  # an arc's excess over its chord, relative
        print(f"K_rest = {k_rest:g} 1/m: shape error {error:.2e} L, the chord deficit {deficit:.2e}")
        assert error < deficit


def test_without_gravity_a_profile_rests_as_its_own_shape(unloaded):
    # The table K_rest(s) (a hinge takes the profile's mean over the arc it bends): the
    # shape θ(s) = ∫K_rest, measured 3.2e-4 L at h = 5 mm (a kink of the profile, at 40 mm,
    # falls on a hinge).
    scenes, result = unloaded
    j = list(UNLOADED).index("table")
    scene, nodes = scenes[j], result.frames[-1, j]
    nc = scene.n_clamped
    s = np.arange(len(nodes) - nc + 1) * scene.spacing
    error = np.abs(nodes[nc - 1 :] - nodes[nc - 1] - exact_hanging_shape(UNLOADED["table"][1], s)).max() / LENGTH_M
    print(f"profile: shape error {error:.2e} L")
    assert error < 1e-3


SET_CASES = {  # q = K_rest L for the reference, and the scene's fields
    "lifting": (1.0, ["strip.rest_curvature_per_cm=0.1"]),
    "curling down": (-1.0, ["strip.rest_curvature_per_cm=-0.1"]),
    "profile": (
        lambda s: 2.0 * s,
        ["strip.rest_curvature_table_s_mm=[0.0, 100.0]", "strip.rest_curvature_table_per_cm=[0.0, 0.2]"],
    ),
}


@pytest.fixture(scope="module")
def settled_with_set():
    """Case, h → tip drop / L, reach / L, last chord's angle of the strip settled
    horizontally with κ = 8 (Peirce's strip) and a set."""
    shapes = {}
    for spacing in (5.0, 2.5):
        scenes = [horizontal_scene(8.0, "second_order", spacing, *extra) for _, extra in SET_CASES.values()]
        result = wc.simulate(scenes)
        for j, name in enumerate(SET_CASES):
            nodes = result.frames[-1, j]
            edge, tip, last = nodes[scenes[j].n_clamped - 1], nodes[-1], nodes[-1] - nodes[-2]
            shapes[(name, spacing)] = (
                (edge[1] - tip[1]) / LENGTH_M,
                (tip[0] - edge[0]) / LENGTH_M,
                math.atan2(-last[1], last[0]),
            )
    return shapes


@pytest.mark.parametrize("name", SET_CASES)
def test_with_gravity_the_set_strip_is_the_heavy_elastica_with_natural_curvature(settled_with_set, name):
    # Measured at h = 5 mm (then 2.5 mm): tip drop lifting +0.468 % (+0.123 %), curling
    # down +0.151 % (+0.042 %), profile +0.403 % (+0.107 %): second order, like the
    # elastica without a set (tests/test_elastica.py). The last chord's angle is the
    # tangent's at s = L − h/2, where a set strip still turns: θ(1) + (h/2L) q(1) (the
    # free end's θ′ = −q): measured +0.445 %, +0.031 %, +0.169 % (+0.127 %, +0.010 %,
    # +0.066 %). The reach is within 0.13 %.
    q, _ = SET_CASES[name]
    exact = heavy_elastica(8.0, natural_curvature=q)
    q_tip = q(1.0) if callable(q) else q
    errors = {}
    for h in (5.0, 2.5):
        drop, reach, angle = settled_with_set[(name, h)]
        chord_angle = exact["tip_angle"] + h * 1e-3 / (2 * LENGTH_M) * q_tip
        errors[h] = (drop / exact["tip_drop"] - 1, reach / exact["tip_reach"] - 1, angle / chord_angle - 1)
    print(
        f"{name}: drop, reach, angle errors "
        + "; ".join(f"h = {h} mm: " + ", ".join(f"{e:+.3%}" for e in v) for h, v in errors.items())
    )
    assert all(abs(e) < 0.005 for e in errors[5.0])
    assert math.log2(abs(errors[5.0][0]) / abs(errors[2.5][0])) > 1.8


@pytest.mark.parametrize("law", BENDING_LAWS)
def test_every_law_started_on_its_rest_arc_stays_there(law):
    # Each law's hinges start fresh at K − K_rest = 0 and no force acts: the strip, placed
    # on the arc of its own natural curvature without gravity, does not move (a law that
    # bent from K, not K − K_rest, would spring straight at once).
    scene = wc.load_scene(
        "damped_swing",
        overrides(
            run__gravity_m_per_s2=0.0,
            release__enabled=False,
            run__duration_s=0.2,
            material__bending_law=law,
            strip__rest_curvature_per_cm=0.3,
        ),
    )
    nc, h, radius = scene.n_clamped, scene.spacing, 1 / 30.0
    start = wc.scene.rest_positions(scene)
    # equal chords h on the circle of radius R tangent to the clamp below its edge; the
    # edge hinge's half segment turns the first chord by ψ with 4 sin(ψ/2) / h = K_rest
    psi = 2 * math.asin(h / (4 * radius))
    step = 2 * math.asin(h / (2 * radius))
    edge = start[nc - 1].copy()
    for i in range(nc, len(start)):
        angle = psi + (i - nc) * step  # of chord i − 1 → i, counter-clockwise from straight down
        start[i] = start[i - 1] + h * np.array([math.sin(angle), -math.cos(angle)])
    result = wc.simulate(scene, initial_positions=start[:, None, :])
    moved = np.abs(result.frames[:, 0] - start[None]).max()
    assert np.isclose(start[nc - 1], edge).all()
    assert moved < 1e-9  # measured ~1e-13 m: rounding
    assert np.abs(result.probe("loop_curvature", 0) - 30.0).max() < 1e-6  # the probe reports the strip's own K


@pytest.mark.parametrize("law", ("tagawa2003", "masing"))
def test_energy_budget_closes_with_a_set_and_a_grip(law):
    # Hysteretic swing with a set, a stiff and more hysteretic grip zone and damping, from
    # the hold and release: kinetic + gravitational + tensile + work against bending and
    # damping stays constant (measured peak-to-peak 0.012 % of the peak kinetic energy,
    # as without them: tests/test_energy.py); the set changes the swing it closes on.
    fields = dict(
        strip__rest_curvature_per_cm=0.15,
        clamp__grip_length_mm=12.0,
        clamp__grip_bending_factor=3.0,
        clamp__grip_hysteresis_factor=2.0,
        material__bending_law=law,
        run__duration_s=1.5,
    )
    result = wc.simulate(wc.load_scene("damped_swing", overrides(**fields)))
    plain = wc.simulate(wc.load_scene("damped_swing", overrides(material__bending_law=law, run__duration_s=1.5)))
    total = result.energy_total()[:, 0]
    scale = result.probe("kinetic", 0).max()
    print(f"{law}: budget peak-to-peak {np.ptp(total) / scale:.2e} of the peak kinetic energy")
    assert np.ptp(total) / scale < 5e-4
    assert np.abs(result.probe("tip_x", 0) - plain.probe("tip_x", 0)).max() > 5e-3


def test_the_set_is_converted_once_to_si():
    scene = wc.load_scene("damped_swing", overrides(strip__rest_curvature_per_cm=0.2))
    batch = wc.scene.build_batch([scene])
    assert np.all(batch.model.rest_curvature == 20.0)  # 1/cm → 1/m
    assert to_si(scene.material).bending_rigidity > 0


def test_a_free_settle_starts_a_set_strip_from_its_own_hanging_shape():
    # release.hold_free_end = false: the pre-roll lets the set strip settle under its own
    # weight, so it is at rest at t = 0, curled (tip 6.9 mm aside for K_rest = 0.2 1/cm);
    # without a pre-roll the same strip starts straight and springs towards its set.
    fields = dict(strip__rest_curvature_per_cm=0.2, run__duration_s=0.1)
    settled = wc.simulate(
        wc.load_scene(
            "damped_swing",
            overrides(release__hold_free_end=False, release__move_time_s=0.1, release__settle_time_s=1.0, **fields),
        )
    )
    straight = wc.simulate(wc.load_scene("damped_swing", overrides(release__enabled=False, **fields)))
    tip = settled.probe("tip_x", 0)
    print(f"settled: tip at {tip[0] * 1e3:.3f} mm, speed {settled.probe('tip_speed', 0)[0]:.2e} m/s")
    assert settled.probe("tip_speed", 0).max() < 1e-4 and np.ptp(tip) < 1e-5
    assert tip[0] > 1e-3
    assert straight.probe("tip_speed", 0).max() > 1e-2
