"""warpcloth against PyElastica on the linear-elastic hanging strip (run by hand, not a test).

    python benchmarks/pyelastica_compare.py [--quick] [--repeat 2]
                                            [--pe-elements 20 40 80] [--wc-spacings 5 2.5 1.25]

The problem is the bundled ``damped_swing`` scene with D1 = 0 (linear bending), γ = 0
(no damping) and the release phase off: the strip hangs from its clamp and starts at rest
in the first mode shape W(ξ) of the clamped hanging beam with a 1 mm tip amplitude. The
exact first period is T = 2π / (λ √(B/(ρ_A L⁴))) from ``warpcloth.calibrate.references.hanging_beam_mode``
(γ = ρ_A g L³ / B ≈ 203, T = 0.50513 s).

PyElastica (a Cosserat rod code) gets the same strip as a round rod hanging along −y:
node 0 and the director of element 0 fixed (``OneEndFixedBC``), ``GravityForces``, no
damper (PyElastica needs none), its ``PositionVerlet`` stepper. The radius matches both
the total bending rigidity EI = B·W and the initial tensile stiffness EA = a1·W:
r = 2√(EI/EA), E = EA/(πr²), ρ·πr² = ρ_A·W, shear modulus G = E/(2(1 + ν)) with ν = 0.5.
Its initial condition: node 1 stays on the clamp axis (the clamped director of element 0
holds it there through the stiff shear), nodes 2… are displaced by the mode shape, and the
directors of elements 1… follow the displaced tangents (a second run with straight
directors checks that this does not matter).

Printed, all measured in the same run:
1. element-steps/s at equal dt (1e-6 s): warpcloth at batch 1 and 1024, PyElastica with
   one rod and with 64 rods in one simulator (element-steps = free segments × steps × strips);
2. the largest stable dt of each code (bisection to 1 % on a short run);
3. wall time per simulated second at that dt, with the first-period error from a real
   run of ~1.8 periods, and the wall-time ratio at equal or better period accuracy.
Timings are the best of ``--repeat`` runs. ``--quick`` shortens spans and drops the
finer resolutions.
"""

from __future__ import annotations

import argparse
import logging
import math
import platform
import time
from collections.abc import Callable
from dataclasses import dataclass

import elastica as ea
import numpy as np
import warp as wp
from elastica.version import VERSION as ELASTICA_VERSION

import warpcloth as wc
from warpcloth.calibrate.references import hanging_beam_mode
from warpcloth.metrics import first_period
from warpcloth.scene import build_batch, rest_positions, to_si
from warpcloth.strip import SemiImplicitEulerSolver, simulate_batch

AMPLITUDE = 1e-3  # m, tip amplitude of the initial mode shape
EQUAL_DT = 1e-6  # s, the common step of the throughput comparison
NU = 0.5  # Poisson ratio for PyElastica's shear modulus
BASE = ["material.hysteresis_d1_gf_cm_per_cm=0.0", "damping.gamma_per_s=0.0", "release.enabled=false"]


@dataclass
class Problem:
    """The strip in SI units, its round-rod equivalent for PyElastica and the exact period."""

    length: float  # free length L, m
    width: float  # m
    gravity: float  # m/s²
    sample_interval: float  # s, warpcloth's probe interval (used for PyElastica too)
    rigidity: float  # EI = B·W, N·m²
    axial: float  # EA = a1·W, N
    line_density: float  # ρ_A·W, kg/m
    radius: float  # m
    youngs: float  # Pa
    shear: float  # Pa
    density: float  # kg/m³
    gamma: float  # ρ_A g L³ / B
    shape: Callable[[np.ndarray], np.ndarray]  # W(ξ), W(1) = 1
    period: float  # exact first period, s


def make_problem() -> Problem:
    """Read the scene and material, derive the round section and the exact period."""
    scene = wc.load_scene("damped_swing", BASE)
    m = to_si(scene.material)
    length, width = scene.strip.free_length_mm * 1e-3, scene.strip.width_mm * 1e-3
    g = scene.run.gravity_m_per_s2
    rigidity = m.bending_rigidity * width  # B is per unit width (N·m); the hinge moment is M·W
    axial = m.tensile[0] * width  # dT/dε at ε = 0 is a1 (N/m per width)
    line_density = m.density * width
    radius = 2.0 * math.sqrt(rigidity / axial)  # EI/EA = r²/4 for a round section
    area = math.pi * radius**2
    youngs = axial / area
    gamma = m.density * g * length**3 / m.bending_rigidity
    lam, shape = hanging_beam_mode(gamma)
    period = 2 * math.pi / (lam * math.sqrt(m.bending_rigidity / (m.density * length**4)))
    return Problem(
        length,
        width,
        g,
        scene.output_interval,
        rigidity,
        axial,
        line_density,
        radius,
        youngs,
        youngs / (2 * (1 + NU)),
        line_density / area,
        gamma,
        shape,
        period,
    )


def wc_scene(spacing_mm: float, dt: float, span: float) -> wc.Scene:
    """The linear-elastic hanging strip at a spacing and step, run for ``span`` seconds."""
    return wc.load_scene(
        "damped_swing",
        [*BASE, f"strip.spacing_mm={spacing_mm!r}", f"integrator.dt_s={dt!r}", f"run.duration_s={span!r}"],
    )


def wc_start(scene: wc.Scene, problem: Problem, batch: int) -> np.ndarray:
    """Straight strip displaced sideways by the mode shape below the clamp edge, [node, strip, xy]."""
    x = rest_positions(scene)
    s_free = np.maximum(0.0, -x[:, 1])
    x[:, 0] = AMPLITUDE * problem.shape(s_free / problem.length) * (s_free > 0)
    return np.repeat(x[:, None, :], batch, axis=1)


@dataclass
class Trace:
    """One run: tip x at sample times, stepping wall time, element-steps done, and whether it stayed bounded."""

    t: np.ndarray
    tip_x: np.ndarray
    wall: float
    element_steps: int
    stable: bool


def run_warpcloth(problem: Problem, spacing_mm: float, dt: float, span: float, batch: int = 1) -> Trace:
    """Simulate ``batch`` copies of the strip; wall time is the stepping loop (RunResult.wall_time_s).

    Through the simulation core, which takes any dt: the scene layer refuses a step past
    the stretching limit, and the bisection for the largest stable dt must step there."""
    scene = wc_scene(spacing_mm, 1e-7, span)  # the scene's own dt is not used: the solver below has dt
    built = build_batch([scene] * batch)
    state = built.model.state()
    state.set_positions(wc_start(scene, problem, batch))
    solver = SemiImplicitEulerSolver(built.model, dt=dt, divergence_strain=scene.integrator.divergence_strain)
    result = simulate_batch(
        built.model, built.control, solver, built.recorder, state, on_divergence="record", keep_frames=False
    )
    tip = result.probe("tip_x", 0)
    free_segments = scene.n_nodes - scene.n_clamped
    stable = not result.diverged and bool(np.all(np.abs(tip) < 2 * AMPLITUDE))
    return Trace(result.t, tip, result.wall_time_s, result.strip_steps * free_segments, stable)


class _Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing):
    pass


def build_pyelastica(
    problem: Problem, n_elements: int, n_rods: int = 1, straight_directors: bool = False
) -> tuple[_Simulator, list[ea.CosseratRod]]:
    """``n_rods`` identical clamped rods in one simulator, started in the mode shape."""
    root = logging.getLogger()
    level = root.level
    root.setLevel(logging.ERROR)  # PyElastica warns that ρI (~1e-13 kg·m) is below its tolerance
    try:
        sim = _Simulator()
        rods = []
        for _ in range(n_rods):
            rod = ea.CosseratRod.straight_rod(
                n_elements,
                np.zeros(3),
                np.array([0.0, -1.0, 0.0]),
                np.array([0.0, 0.0, 1.0]),
                problem.length,
                problem.radius,
                problem.density,
                youngs_modulus=problem.youngs,
                shear_modulus=problem.shear,
            )
            sim.append(rod)
            sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))
            sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, -problem.gravity, 0.0]))
            rods.append(rod)
        sim.finalize()  # the clamp keeps node 0 and the straight director of element 0
    finally:
        root.setLevel(level)
    s = np.linspace(0.0, problem.length, n_elements + 1)
    x = AMPLITUDE * problem.shape(s / problem.length)
    x[:2] = 0.0  # node 0 clamped, node 1 held on the axis by element 0's clamped director
    for rod in rods:
        rod.position_collection[0, :] = x
        if not straight_directors:
            e = np.diff(rod.position_collection, axis=1)[:, 1:]
            tangent = e / np.linalg.norm(e, axis=0)
            normal = np.repeat(np.array([[0.0], [0.0], [1.0]]), n_elements - 1, axis=1)
            rod.director_collection[0, :, 1:] = normal
            rod.director_collection[1, :, 1:] = np.cross(tangent, normal, axis=0)
            rod.director_collection[2, :, 1:] = tangent
    return sim, rods


def run_pyelastica(
    problem: Problem, n_elements: int, dt: float, span: float, n_rods: int = 1, straight_directors: bool = False
) -> Trace:
    """Step PositionVerlet for ``span`` seconds; the tip of rod 0 is sampled at warpcloth's probe rate."""
    sim, rods = build_pyelastica(problem, n_elements, n_rods, straight_directors)
    stepper = ea.PositionVerlet()
    steps = round(span / dt)
    every = max(1, round(problem.sample_interval / dt))
    t, ts, xs = np.float64(0.0), [0.0], [float(rods[0].position_collection[0, -1])]
    stable, done = True, 0
    start = time.perf_counter()
    for i in range(1, steps + 1):
        t = stepper.step(sim, t, dt)
        done = i
        if i % every == 0:
            tip = float(rods[0].position_collection[0, -1])
            ts.append(float(t))
            xs.append(tip)
            if not abs(tip) < 2 * AMPLITUDE:  # also catches NaN
                stable = False
                break
    wall = time.perf_counter() - start
    stable = stable and bool(np.all(np.isfinite(rods[0].position_collection)))
    return Trace(np.array(ts), np.array(xs), wall, n_elements * n_rods * done, stable)


def largest_stable_dt(is_stable: Callable[[float], bool], guess: float, rel: float = 0.01) -> float:
    """Largest dt with ``is_stable(dt)``, by doubling/halving from ``guess`` then bisecting to ``rel``."""
    lo, hi = guess, guess
    while is_stable(hi):
        lo, hi = hi, 2 * hi
    while not is_stable(lo):
        lo, hi = lo / 2, lo
    while hi / lo > 1 + rel:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if is_stable(mid) else (lo, mid)
    return lo


def mode_residual(trace: Trace, period: float) -> float:
    """RMS of what a single sinusoid at the measured period does not explain, / its amplitude.

    Small for a clean first mode; second-mode content shows up here.
    """
    omega = 2 * math.pi / period
    basis = np.stack([np.ones_like(trace.t), np.cos(omega * trace.t), np.sin(omega * trace.t)], axis=1)
    coef, *_ = np.linalg.lstsq(basis, trace.tip_x, rcond=None)
    residual = trace.tip_x - basis @ coef
    return float(np.sqrt(np.mean(residual**2)) / math.hypot(coef[1], coef[2]))


@dataclass
class Row:
    """One line of the accuracy table."""

    code: str
    resolution: str
    dt: float
    wall_per_s: float
    period: float
    error: float
    residual: float


def timed(run: Callable[[], Trace], repeat: int) -> tuple[Trace, float]:
    """The last trace and the best wall time of ``repeat`` identical runs."""
    best, trace = math.inf, None
    for _ in range(repeat):
        trace = run()
        best = min(best, trace.wall)
    assert trace is not None
    return trace, best


def confirmed(run: Callable[[float], Trace], dt: float) -> tuple[float, Trace]:
    """Run at ``dt``; if that longer run is not stable after all, step dt down by 1 % until it is."""
    for _ in range(10):
        trace = run(dt)
        if trace.stable:
            return dt, trace
        dt *= 0.99
    raise RuntimeError(f"no stable dt found down to {dt:.3g} s")


def accuracy_row(
    code: str, resolution: str, dt: float, trace: Trace, wall: float, span: float, problem: Problem
) -> Row:
    """Period, error vs the exact T and mode cleanliness of a finished run."""
    if not trace.stable:
        raise RuntimeError(f"{code} {resolution} at dt = {dt:.3g} s diverged in the period run")
    period = first_period(trace.t, trace.tip_x, level=0.0)
    return Row(code, resolution, dt, wall / span, period, period / problem.period - 1, mode_residual(trace, period))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="short spans, PyElastica 20 elements, h = 5 mm only")
    parser.add_argument("--repeat", type=int, default=2, help="timed runs per measurement; the best is kept")
    parser.add_argument("--pe-elements", type=int, nargs="+", help="PyElastica resolutions (default 20 40 80)")
    parser.add_argument("--wc-spacings", type=float, nargs="+", help="warpcloth spacings in mm (default 5 2.5 1.25)")
    parser.add_argument("--pe-rods", type=int, default=64, help="rods in the multi-rod PyElastica simulator")
    parser.add_argument("--batch", type=int, default=1024, help="warpcloth batch for the batched throughput row")
    args = parser.parse_args()
    quick = args.quick
    pe_elements = args.pe_elements or ([20] if quick else [20, 40, 80])
    wc_spacings = args.wc_spacings or ([5.0] if quick else [5.0, 2.5, 1.25])
    span = 0.7 if quick else 0.9  # ~1.4–1.8 periods: three zero crossings
    stability_span = 0.03 if quick else 0.05

    wp.config.log_level = logging.WARNING
    wp.init()
    problem = make_problem()
    p = problem
    print(
        f"machine: {platform.machine()}, {platform.system()}, device cpu (warp {wp.__version__}, float64), "
        f"pyelastica {ELASTICA_VERSION} (numba), numpy {np.__version__}"
    )
    print(
        f"strip: L = {p.length * 1e3:g} mm, W = {p.width * 1e3:g} mm, EI = B·W = {p.rigidity:.4e} N·m², "
        f"EA = a1·W = {p.axial:.4e} N, ρ_A·W = {p.line_density:.4e} kg/m"
    )
    print(
        f"round rod for PyElastica: r = 2√(EI/EA) = {p.radius * 1e3:.4f} mm, E = {p.youngs:.4e} Pa, "
        f"G = E/(2(1+{NU})) = {p.shear:.4e} Pa, ρ = {p.density:.4e} kg/m³; no damper"
    )
    print(
        f"exact: γ = {p.gamma:.1f}, T = {p.period:.5f} s; start at rest in W(ξ), tip amplitude "
        f"{AMPLITUDE * 1e3:g} mm; timings best of {args.repeat}"
    )

    # Warm up: compile the Warp kernels and PyElastica's numba functions before any timing.
    run_warpcloth(p, 5.0, EQUAL_DT, 0.01)
    run_pyelastica(p, pe_elements[0], EQUAL_DT, 1e-4)
    run_pyelastica(p, pe_elements[0], EQUAL_DT, 1e-4, n_rods=2)

    # 1. Throughput at equal dt.
    n_free = round(p.length / wc_scene(5.0, EQUAL_DT, 0.01).spacing)
    runs = [
        ("warpcloth", 1, lambda: run_warpcloth(p, 5.0, EQUAL_DT, 0.05 if quick else 0.1)),
        ("warpcloth", args.batch, lambda: run_warpcloth(p, 5.0, EQUAL_DT, 0.005 if quick else 0.01, args.batch)),
        ("PyElastica", 1, lambda: run_pyelastica(p, n_free, EQUAL_DT, 0.02 if quick else 0.05)),
        (
            "PyElastica",
            args.pe_rods,
            lambda: run_pyelastica(p, n_free, EQUAL_DT, 0.002 if quick else 0.005, args.pe_rods),
        ),
    ]
    rates = {}
    for code, strips, run in runs:
        trace, wall = timed(run, args.repeat)
        rates[code, strips] = trace.element_steps / wall
    pe_one, pe_many = rates["PyElastica", 1], rates["PyElastica", args.pe_rods]
    print(
        f"\n1. Equal dt = {EQUAL_DT:g} s, h = 5 mm / {n_free} elements "
        f"(element-steps = {n_free} free segments × steps × strips)"
    )
    print(
        f"{'code':>10} {'strips':>6} {'element-steps/s':>16} {'vs PyElastica 1 rod':>20} "
        f"{f'vs PyElastica {args.pe_rods} rods':>21}"
    )
    for (code, strips), rate in rates.items():
        print(f"{code:>10} {strips:>6} {rate:>16.3e} {rate / pe_one:>19.1f}x {rate / pe_many:>20.1f}x")

    # 2. Largest stable dt (short runs from the mode-shape start; 1 % bisection).
    print(f"\n2. Largest stable dt (bisection to 1 % on {stability_span:g} s runs, then confirmed over {span:g} s)")
    dt_max: dict[tuple[str, float], float] = {}
    for h in wc_spacings:
        dt_max["warpcloth", h] = largest_stable_dt(
            lambda dt, h=h: run_warpcloth(p, h, dt, stability_span).stable, 1e-5 * h / 5
        )
        estimate = h * 1e-3 * math.sqrt(p.line_density / p.axial)  # 2/ω, ω = (2/h)√(EA/(ρ_A W))
        print(
            f"warpcloth  h = {h:g} mm: {dt_max['warpcloth', h]:.3e} s "
            f"(axial mode estimate h√(ρ_A W/EA) = {estimate:.3e} s)"
        )
    kappa_g = 27 / 28 * p.shear  # PyElastica's Timoshenko shear factor
    estimate = p.radius * math.sqrt(p.density / kappa_g)  # 2/ω, ω² = κGA/(ρI) = (4/r²)(κG/ρ)
    for n in pe_elements:
        dt_max["PyElastica", n] = largest_stable_dt(
            lambda dt, n=n: run_pyelastica(p, n, dt, stability_span).stable, 1e-6
        )
        print(
            f"PyElastica {n} elements: {dt_max['PyElastica', n]:.3e} s "
            f"(shear-rotation estimate r√(ρ/κG) = {estimate:.3e} s)"
        )

    # 3. Wall time per simulated second and first-period error, each at its largest stable dt
    # (confirmed on the full period run; stepped down by 1 % if that run is not stable after all).
    rows: list[Row] = []
    wc_max: dict[float, Row] = {}
    pe_max: dict[int, Row] = {}
    timing_span = 10 * span  # warpcloth is fast: time a longer run for a steadier number
    default = wc.load_scene("damped_swing").integrator.dt_s
    for h in wc_spacings:
        dt, trace = confirmed(lambda dt, h=h: run_warpcloth(p, h, dt, span), dt_max["warpcloth", h])
        dt_max["warpcloth", h] = dt
        _, wall = timed(lambda h=h, dt=dt: run_warpcloth(p, h, dt, timing_span), args.repeat)
        wc_max[h] = accuracy_row("warpcloth", f"h = {h:g} mm, max dt", dt, trace, wall, timing_span, p)
        rows.append(wc_max[h])
        if h == 5.0:
            trace = run_warpcloth(p, h, default, span)
            _, wall = timed(lambda h=h: run_warpcloth(p, h, default, timing_span), args.repeat)
            rows.append(accuracy_row("warpcloth", f"h = {h:g} mm, scene dt", default, trace, wall, timing_span, p))
    for n in pe_elements:
        dt, trace = confirmed(lambda dt, n=n: run_pyelastica(p, n, dt, span), dt_max["PyElastica", n])
        dt_max["PyElastica", n] = dt
        wall = trace.wall
        if args.repeat > 1:
            wall = min(wall, timed(lambda n=n, dt=dt: run_pyelastica(p, n, dt, span), args.repeat - 1)[1])
        pe_max[n] = accuracy_row("PyElastica", f"{n} elements, max dt", dt, trace, wall, span, p)
        rows.append(pe_max[n])
    n0 = pe_elements[0]
    checks = []  # the straight-director start, at the max dt and at half of it
    for first_dt in (dt_max["PyElastica", n0], dt_max["PyElastica", n0] / 2):
        dt, check = confirmed(lambda dt: run_pyelastica(p, n0, dt, span, straight_directors=True), first_dt)
        checks.append(accuracy_row("PyElastica", "straight directors", dt, check, check.wall, span, p))

    print(
        f"\n3. At the largest stable dt: wall time per simulated second (best of {args.repeat}; warpcloth timed "
        f"on {10 * span:g} s, PyElastica on the {span:g} s period run); first period from a {span:g} s run"
    )
    print(
        f"{'code':>10} {'resolution':>24} {'dt [s]':>10} {'wall/sim s':>11} {'period [s]':>11} {'error':>8} "
        f"{'non-mode rms':>13}"
    )
    for r in rows:
        print(
            f"{r.code:>10} {r.resolution:>24} {r.dt:>10.3e} {r.wall_per_s:>11.4f} {r.period:>11.5f} "
            f"{r.error:>+8.3%} {r.residual:>13.2e}"
        )
    for c in checks:
        print(
            f"(PyElastica {n0} elements started with straight directors instead, dt = {c.dt:.3e} s: "
            f"period {c.period:.5f} s, error {c.error:+.3%}, non-mode rms {c.residual:.2e})"
        )

    print(
        "\nWall-time ratio PyElastica / warpcloth, each at its max dt: warpcloth at the same resolution "
        "(h = L/n), and at the coarsest spacing whose |period error| ≤ PyElastica's"
    )
    print(
        f"{'PyElastica':>12} {'error':>8} | {'same h':>9} {'error':>8} {'ratio':>6} | {'|err| ≤':>9} {'error':>8} "
        f"{'ratio':>6}"
    )
    for n, pe in pe_max.items():
        same = next((wc_max[h] for h in wc_max if math.isclose(h * n, p.length * 1e3)), None)
        better = [h for h in wc_max if abs(wc_max[h].error) <= abs(pe.error)]
        h_better = max(better) if better else min(wc_max)  # the finest shown if none is as accurate
        line = f"{n:>3} elements {pe.error:>+8.3%} | "
        if same is not None:
            h_same = p.length * 1e3 / n
            line += f"{h_same:>6g} mm {same.error:>+8.3%} {pe.wall_per_s / same.wall_per_s:>5.0f}x | "
        else:
            line += f"{'-':>9} {'':>8} {'':>6} | "
        best = wc_max[h_better]
        line += f"{h_better:>6g} mm {best.error:>+8.3%} {pe.wall_per_s / best.wall_per_s:>5.0f}x"
        print(line + ("" if better else "  (none as accurate: finest shown)"))


if __name__ == "__main__":
    main()
