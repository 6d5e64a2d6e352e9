"""The hysteretic bending law (paper eqs. 3-4, docs/model.md §4) on a single hinge.

Runs the kernel's own hinge logic through warpcloth.strip.moment_along_path.
"""

import math

import numpy as np
import pytest
from conftest import loop_asymptote_of, overrides, paper_loop  # noqa: F401  (keeps Warp quiet)

from warpcloth.scene import MaterialSection, to_si
from warpcloth.strip import MaterialSI, moment_along_path

DEFAULT = to_si(MaterialSection())


def branches(m: MaterialSI, k):
    """Eq. 3a (rising) and 3b (falling) of the loop centred on K = 0."""
    a, k0, d1 = m.bending.hysteresis_alpha, m.bending.hysteresis_k0, m.bending.hysteresis_d1
    up = m.bending_rigidity * k + loop_asymptote_of(m) - d1 * np.exp(-a * (k0 + k))
    down = m.bending_rigidity * k - loop_asymptote_of(m) + d1 * np.exp(-a * (k0 - k))
    return up, down


def ramp(*points, n=4000):
    """Piecewise-linear curvature path through the points, n samples per leg."""
    legs = [np.linspace(a, b, n, endpoint=False) for a, b in zip(points[:-1], points[1:], strict=True)]
    return np.concatenate(legs + [np.array([points[-1]])])


def test_major_cycle_reproduces_eq3():
    # 0 → K0 → −K0 → K0 with the default material. The fresh hinge starts with H = 0 at
    # K = 0, so at K0 its offset falls short of the centred loop's by ½ D1 e^{−αK0}
    # (exactly: the rising branch through (0, 0) vs eq. 3a). The falling leg therefore
    # starts that far from eq. 3b and converges to it (the gap shrinks as e^{α(u−K0)});
    # at −K0 it is ½ D1 e^{−3αK0} ≈ 1e-20 N, so the rising leg is eq. 3a to rounding.
    m = DEFAULT
    k0, a, d1 = m.bending.hysteresis_k0, m.bending.hysteresis_alpha, m.bending.hysteresis_d1
    n = 4000
    k = ramp(0.0, k0, -k0, k0, n=n)
    moment, _ = moment_along_path(m, k)
    up, down = branches(m, k)
    falling = slice(n, 2 * n)
    rising = slice(2 * n, 3 * n + 1)
    gap = np.abs(moment[falling] - down[falling])
    first_gap = 0.5 * d1 * math.exp(-a * k0)
    assert gap[0] == pytest.approx(first_gap, rel=1e-6)
    assert np.all(gap <= first_gap * np.exp(a * (k[falling] - k0)) * (1 + 1e-6) + 1e-17)
    assert np.max(np.abs(moment[rising] - up[rising])) < 1e-12 * d1
    # The loop closes at ±K0 (the KES loop's end points).
    assert up[-1] == pytest.approx(down[-1], abs=1e-12 * d1)


def test_loop_translation_converges_to_centred_loop_for_soft_saturation():
    # α K0 = 0.5: the branches never saturate, so the first cycles are translated loops;
    # the symmetric loop is the fixed point the reversal rule must converge to.
    m = MaterialSI(0.2, (1e3, 0, 0, 0), 1e-5, paper_loop(4e-4, 0.005, 100.0))
    k0 = m.bending.hysteresis_k0
    k = ramp(0.0, *([k0, -k0] * 12), k0, n=2000)
    moment, _ = moment_along_path(m, k)
    up, down = branches(m, k)
    last_falling = slice(len(k) - 1 - 2 * 2000 + 1, len(k) - 1 - 2000)
    last_rising = slice(len(k) - 1 - 2000 + 1, len(k))
    # Measured contraction per cycle is ≈ e^{−2αK0}·… ; after 12 cycles the offset from
    # the centred loop is below 1e-6·D1.
    tol = 1e-6 * m.bending.hysteresis_d1
    assert np.max(np.abs(moment[last_falling] - down[last_falling])) < tol
    assert np.max(np.abs(moment[last_rising] - up[last_rising])) < tol


def lipschitz_bound(m: MaterialSI) -> float:
    # |dM/dK| ≤ D + α(M0 + |H|) ≤ D + 2αM0 on either branch (h' = α(M0 ∓ h)).
    return m.bending_rigidity + 2 * m.bending.hysteresis_alpha * loop_asymptote_of(m)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_moment_continuous_at_every_reversal_and_offset_bounded(seed):
    # A random walk with many reversals and small inner loops, in tiny steps. A jump in
    # M at a reversal would exceed the Lipschitz bound of the branches by orders of
    # magnitude (steps are 1e-4 of K0, a jump would be O(M0)).
    rng = np.random.default_rng(seed)
    m = DEFAULT
    step = 1e-4 * m.bending.hysteresis_k0
    direction = np.where(rng.random(60) < 0.5, -1.0, 1.0)
    lengths = rng.integers(3, 3000, size=60)
    k = np.concatenate([[0.0], np.cumsum(np.repeat(direction, lengths) * step)])
    moment, _ = moment_along_path(m, k)
    jumps = np.abs(np.diff(moment))
    assert np.all(jumps <= lipschitz_bound(m) * np.abs(np.diff(k)) * (1 + 1e-9) + 1e-15)
    offset = moment - m.bending_rigidity * k
    assert np.all(np.abs(offset) < loop_asymptote_of(m))
    reversals = np.count_nonzero(np.diff(np.sign(np.diff(k))))
    assert reversals > 30


def closed_form_offsets(m: MaterialSI, k: np.ndarray) -> np.ndarray:
    """The offset M − D K along ``k`` by §4.2-4.3 as the paper writes it, independently of
    the kernel: each branch is h_s(K − c) about a loop centre c, and a reversal moves c by
    the inverse branch (a logarithm) so that h stays continuous."""
    b = m.bending
    d1, a, k0, m0 = b.hysteresis_d1, b.hysteresis_alpha, b.hysteresis_k0, loop_asymptote_of(m)

    def h(u: float, s: float) -> float:
        return s * (m0 - d1 * math.exp(-a * (k0 + s * u)))

    s, c = 1.0, k[0] + k0 + math.log(m0 / d1) / a  # fresh: rising, h = 0 at k[0]
    out = np.empty(len(k))
    out[0] = 0.0
    for n in range(1, len(k)):
        if (k[n] - k[n - 1]) * s < 0:
            held = h(k[n - 1] - c, s)
            s = -s
            c = k[n - 1] + s * k0 + s * math.log((m0 - s * held) / d1) / a
        out[n] = h(k[n] - c, s)
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_the_kernels_step_by_step_branch_is_the_papers_closed_form(seed):
    # The kernel carries each hinge's gap to its branch's asymptote, g = M0 − s h, and
    # integrates the branch exactly over each step (g ← g e^{−α s ΔK}; at a reversal
    # g ← 2 M0 − g): no logarithm, no loop centre. Over a walk of 10^4 steps with ~40
    # changes of direction, inner loops down to a few steps and ~2000 reversals by rounding
    # alone (steps of 1e-13 K0 back, as a hinge at rest sees), it must be the paper's closed
    # form to rounding: the product of the steps' exponentials drifts by ~√n ulp.
    rng = np.random.default_rng(seed)
    m = DEFAULT
    k0 = m.bending.hysteresis_k0
    direction = np.where(rng.random(80) < 0.5, -1.0, 1.0)
    lengths = rng.integers(2, 250, size=80)
    walk = np.repeat(direction, lengths) * 2e-3 * k0
    walk[rng.random(len(walk)) < 0.1] *= -1e-10  # rounding-sized steps back
    k = np.concatenate([[0.0], np.cumsum(walk)])
    moment, _ = moment_along_path(m, k)
    offset = moment - m.bending_rigidity * k
    reference = closed_form_offsets(m, k)
    assert np.count_nonzero(np.diff(np.sign(np.diff(k)))) > 100
    assert np.abs(offset - reference).max() < 1e-13 * loop_asymptote_of(m)


def test_a_reversal_from_a_saturated_branch_is_exactly_continuous():
    # Bent far past K0 the offset reaches its asymptote: g underflows to 0 and h = M0
    # exactly. The loop centre of the closed form would be at infinity there (it used to
    # take a margin of 1e-12 M0, a jump of that size at the reversal); the gap needs none:
    # the falling branch starts at h = M0 with g = 2 M0, h = −M0 + 2 M0 e^{α (K − K_r)}.
    # (D tiny, so that D K at α K = 800 does not round away the offset's last digits)
    m = MaterialSI(0.2, (1e3, 0, 0, 0), 1e-12, paper_loop(4e-4, 0.005, 100.0))
    k0, a, m0 = m.bending.hysteresis_k0, m.bending.hysteresis_alpha, loop_asymptote_of(m)
    far = 800.0 / a  # α·(K − c) ≈ 800: e^{−800} underflows
    k = np.concatenate([np.linspace(0.0, far, 4001), far - np.linspace(0.0, 2 * k0, 2001)[1:]])
    moment, _ = moment_along_path(m, k)
    offset = moment - m.bending_rigidity * k
    assert offset[4000] == pytest.approx(m0, rel=1e-15)
    falling = k[4001:]
    expected = -m0 + 2 * m0 * np.exp(a * (falling - far))
    assert abs(offset[4001] - expected[0]) < 1e-15 * m0  # the margin's jump was 1e-12 M0
    # along the branch, the product of 2000 steps' exponentials: ~n/2 ulp at most
    assert np.abs(offset[4001:] - expected).max() < 1e-13 * m0


def test_zero_d1_is_linear_elastic():
    m = MaterialSI(0.2, (1e3, 0, 0, 0), to_si(MaterialSection()).bending_rigidity, paper_loop(0.0, 0.05, 250.0))
    k = np.sin(np.linspace(0, 20, 5001)) * 300.0
    moment, _ = moment_along_path(m, k)
    np.testing.assert_array_equal(moment, m.bending_rigidity * k)


def cycle_work_error(m: MaterialSI, n: int) -> tuple[float, float, float]:
    """(work over one closed −K0 → K0 → −K0 cycle − analytic loop area, area, bound)."""
    k0 = m.bending.hysteresis_k0
    warmup = ramp(0.0, *([k0, -k0] * 12), n=n)  # reach the centred loop first
    _, work_warmup = moment_along_path(m, warmup)
    cycle = ramp(-k0, k0, -k0, n=n)
    _, work = moment_along_path(m, np.concatenate([warmup, cycle[1:]]))
    a = m.bending.hysteresis_alpha
    # ∮ M dK of eq. 3 (the elastic part D K integrates to zero over a closed cycle).
    area = 4 * loop_asymptote_of(m) * k0 - 2 * m.bending.hysteresis_d1 * (1 - math.exp(-2 * a * k0)) / a
    # Left-point rule: |error| ≤ ½ Σ |ΔM||ΔK| ≤ ½ L ΔK · (4 K0) with L the Lipschitz
    # bound of the branches; plus the warm-up's residual offset (≤ 1e-6 D1) over 4 K0.
    dk = 2 * k0 / n
    bound = 0.5 * lipschitz_bound(m) * dk * 4 * k0 + 1e-6 * m.bending.hysteresis_d1 * 4 * k0
    return work[0] - work_warmup[0] - area, area, bound


@pytest.mark.parametrize("alpha_k0", [12.5, 0.5])
def test_closed_cycle_work_equals_loop_area(alpha_k0):
    base = DEFAULT
    k0 = 250.0
    m = MaterialSI(
        base.density, base.tensile, base.bending_rigidity, paper_loop(base.bending.hysteresis_d1, alpha_k0 / k0, k0)
    )
    error, area, bound = cycle_work_error(m, 5000)
    assert area > 0
    assert abs(error) <= bound
    # ... and the error is the quadrature's: first order in ΔK, so 4× the samples
    # divide it by 4 (measured 0.250 for both materials).
    finer, _, _ = cycle_work_error(m, 20000)
    assert 0.2 < finer / error < 0.3


def frame_curvature(frames, node):
    """Circumcircle curvature at ``node`` of frames [frame, node, xy] (the kernel's formula)."""
    e1 = frames[:, node] - frames[:, node - 1]
    e2 = frames[:, node + 1] - frames[:, node]
    cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    lengths = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(e1 + e2, axis=1)
    return 2 * cross / lengths


@pytest.mark.parametrize("edge", ["paper", "second_order"])
@pytest.mark.parametrize("hinge_mm", [0.0, 20.0])
def test_loop_probe_records_the_chosen_hinge(hinge_mm, edge):
    # The probed curvature is that hinge's curvature one substep before the recorded
    # node positions: its gap to the frames' circumcircle curvature halves with dt
    # (measured 7.3e-3 → 3.7e-3 → 1.8e-3 1/m at 20 mm), while the neighbouring hinges
    # differ by 2.5–3.6 1/m. The probed moment obeys the law: exactly D K without
    # hysteresis, within ±M0 of D K with it, tracing a loop that dissipates. With the
    # second-order edge, the clamp-edge hinge bends half a segment: twice the turning
    # angle's circumcircle curvature (docs/model.md §5.3).
    import warpcloth as wc

    scale = 2.0 if edge == "second_order" and hinge_mm == 0.0 else 1.0

    for d1 in (0.0, 0.04):
        gaps = []
        for dt in (1e-5, 5e-6):
            scene = wc.load_scene(
                "damped_swing",
                overrides(
                    run__duration_s=0.6,
                    output__loop_hinge_mm=hinge_mm,
                    material__hysteresis_d1_gf_cm_per_cm=d1,
                    integrator__dt_s=dt,
                    clamp__edge_hinge=edge,
                ),
            )
            result = wc.simulate(scene)
            curvature, moment = result.probe("loop_curvature", 0), result.probe("loop_moment", 0)
            node = scene.n_clamped - 1 + scene.loop_hinge
            at_frames = curvature[:: scene.output.probes_per_frame]
            expected = [(scale if o == 0 else 1.0) * frame_curvature(result.frames[:, 0], node + o) for o in (0, 1)]
            gaps.append([np.abs(at_frames - e).max() for e in expected])
        (coarse, neighbour), (fine, _) = gaps
        assert 1.7 < coarse / fine < 2.3 and fine < 0.01 * neighbour
        material = to_si(scene.material)
        offset = moment - material.bending_rigidity * curvature
        if d1 == 0.0:
            assert np.abs(offset).max() <= 1e-12 * np.abs(moment).max()
        else:
            assert 0.1 * loop_asymptote_of(material) < np.abs(offset).max() < loop_asymptote_of(material)
            assert np.sum(0.5 * (moment[1:] + moment[:-1]) * np.diff(curvature)) > 0  # ∮ M dK > 0


def test_loop_hinge_must_be_a_hinge():
    import warpcloth as wc

    for bad in (2.5, 100.0):
        with pytest.raises(wc.SceneError, match=r"output\.loop_hinge_mm"):
            wc.load_scene("damped_swing", [f"output.loop_hinge_mm={bad}"])
