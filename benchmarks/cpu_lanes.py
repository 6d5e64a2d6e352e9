"""Would strips in SIMD lanes speed up warpcloth's CPU step? (run by hand; issue 41)

    python benchmarks/cpu_lanes.py [--strips 1024] [--steps 1000] [--lanes 4 8] [--law tagawa2003]

The Numba port (benchmarks/numba_peer.py) runs strips as SIMD lanes; warpcloth's CPU
kernel gives each thread one strip. This measures the strip's own force pass
(kernels/forces.py: tension, hinge geometry and bending law) with a node update, one strip
per thread (a hinge at a time), against a kernel that calls the same functions
(``segment_and_curvature``, the law's ``follow``, ``hinge_couple``) for one group of L
strips per thread, lanes innermost at each node (the layout a compiler can vectorise:
[node, strip] arrays hold a group's strips side by side), each lane carrying its segment
down the chain as the pass does. The strips are the variants of the bundled sweep (each
its own D, D1, α), started turned by angles of their own and swinging under gravity from
a fixed clamp; both ways end bitwise the same (positions, velocities and every hinge's
memory, checked). Each runs with the sweep's hysteresis and without it (D1 = 0, the law's
elastic limit), which tells what a lane rewrite of the fused kernel could gain and what
stands in its way. One CPU thread; results in benchmarks/RESULTS.md.

Then ``exp`` itself: Warp's CPU compiler leaves it a scalar library call, but a kernel can
call glibc's vector exp (libmvec: 4 float64 a call with AVX2, 8 with AVX-512) through
``wp.func_native``, as the force pass now does for the paper's law (kernels/exp_lanes.py).
The last lines time one exp each way and give their largest difference (libmvec promises
4 ulp).
"""

import argparse
import logging
import platform
import time

import numpy as np
import warp as wp
from warpcloth.kernels import exp_lanes, forces, integrators, structs
from warpcloth.kernels.status import STATUS_OK

import warpcloth as wc
from warpcloth.scene.build import build_batch

f64 = wp.float64
vec2 = wp.types.vector(2, f64)
zero, one = f64(0.0), f64(1.0)


def kernels(lanes: int) -> tuple:
    """The per-strip kernel (the strip's own force pass, kernels/forces.py) and the lane
    kernel calling the same segment-and-hinge function for ``lanes`` strips at each node."""
    strip = structs.build(f64, ())
    StripModel, StripState = strip.StripModel, strip.StripState
    Stepping = integrators.build(f64).Stepping
    pass_ = forces.build(f64)  # a hinge at a time (its exponentials one by one)
    accumulate_internal_forces = pass_.accumulate_internal_forces
    segment_and_curvature, hinge_couple, law = pass_.segment_and_curvature, pass_.hinge_couple, strip.law
    lane_vectors = wp.types.matrix(shape=(lanes, 2), dtype=f64)  # a vec2 per lane, carried down the chain
    lane_scalars = wp.types.vector(lanes, f64)

    @wp.func
    def clear(state: StripState, s: int, i: int):
        state.force_tensile[i, s] = vec2()
        state.force_elastic[i, s] = vec2()
        state.force_hysteretic[i, s] = vec2()

    @wp.func
    def segment_and_hinge(
        model: StripModel,
        stepping: Stepping,
        state: StripState,
        s: int,
        i: int,
        node: vec2,
        e1: vec2,
        inverse_l1: f64,
        width: f64,
        a: wp.types.vector(4, f64),
        p: law.Parameters,
        edge_scale: f64,
        inverse_l0: f64,
    ):
        # the force pass's body for one hinge (kernels/forces.py taking a hinge at a time)
        code, value, following, e2, inverse_l2, curvature = segment_and_curvature(
            model, stepping, state, s, i, node, e1, inverse_l1, width, a, edge_scale, inverse_l0
        )
        if code == STATUS_OK:
            h = i - model.n_clamped + 1
            memory = law.follow(curvature, state.hinge[h, s], p, state.history, h, s)
            hinge_couple(model, state, s, i, h, curvature, memory, p, width, e1, inverse_l1, e2, inverse_l2)
        return code, value, following, e2, inverse_l2

    @wp.func
    def update(model: StripModel, state: StripState, s: int, i: int, dt: f64):
        # semi-implicit Euler under the internal forces and gravity (no drive: a timing probe);
        # the free end carries half a segment
        m = model.node_mass[s]
        if i == model.n_nodes - 1:
            m = m * f64(0.5)
        f = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
        v = state.velocity[i, s] + (f + m * vec2(zero, -model.gravity)) * (dt / m)
        state.velocity[i, s] = v
        state.position[i, s] = state.position[i, s] + v * dt

    @wp.kernel(module="unique", enable_backward=False)
    def per_strip(model: StripModel, stepping: Stepping, state: StripState, steps: int):
        s = wp.tid()
        for _k in range(steps):
            code, _index, _value = accumulate_internal_forces(model, stepping, state, s)
            if code != STATUS_OK:
                return
            for i in range(model.n_clamped, model.n_nodes):
                update(model, state, s, i, stepping.dt)

    @wp.kernel(module="unique", enable_backward=False)
    def in_lanes(model: StripModel, stepping: Stepping, state: StripState, steps: int):
        g = wp.tid()
        first = model.n_clamped - 2
        inverse_l0 = one / model.rest_length
        for _k in range(steps):
            nodes = lane_vectors()
            above = lane_vectors()
            inverse = lane_scalars()
            for j in range(wp.static(lanes)):
                s = g * wp.static(lanes) + j
                clear(state, s, first)
                clear(state, s, first + 1)
                node = state.position[first + 1, s]
                e1 = node - state.position[first, s]
                nodes[j] = node
                above[j] = e1
                inverse[j] = one / wp.length(e1)
            bad = int(0)  # noqa: UP018 (Warp: a variable the loop below reassigns)
            for i in range(first + 1, model.n_nodes - 1):
                for j in range(wp.static(lanes)):
                    s = g * wp.static(lanes) + j
                    code, _value, node, e1, inverse_l1 = segment_and_hinge(
                        model,
                        stepping,
                        state,
                        s,
                        i,
                        nodes[j],
                        above[j],
                        inverse[j],
                        model.width[s],
                        model.tensile[s],
                        model.bending[s],
                        model.edge_curvature_scale[s],
                        inverse_l0,
                    )
                    bad = bad | code
                    nodes[j] = node
                    above[j] = e1
                    inverse[j] = inverse_l1
            if bad != 0:
                return
            for i in range(model.n_clamped, model.n_nodes):
                for j in range(wp.static(lanes)):
                    update(model, state, g * wp.static(lanes) + j, i, stepping.dt)

    return per_strip, in_lanes


def exp_timing(width: int, reps: int = 20000, groups: int = 256, repeats: int = 3) -> None:
    """ns per exp of ``wp.exp`` and of libmvec's ``width``-wide exp (best of ``repeats``), and
    their largest difference on one call each, in units in the last place."""
    exp_of_lanes = exp_lanes.build(f64, width)  # what the force pass calls (kernels/exp_lanes.py)
    lanes = wp.types.vector(width, f64)

    @wp.kernel(module="unique", enable_backward=False)
    def scalar_exp(x: wp.array2d(dtype=f64), out: wp.array2d(dtype=f64), reps: int):
        g = wp.tid()
        for j in range(wp.static(width)):
            a = x[g, j]
            total = zero
            for _r in range(reps):
                total = total + wp.exp(a)
                a = a + f64(1e-9)
            out[g, j] = total

    @wp.kernel(module="unique", enable_backward=False)
    def one_call(x: wp.array2d(dtype=f64), scalar: wp.array2d(dtype=f64), vector: wp.array2d(dtype=f64)):
        g = wp.tid()
        a = lanes()
        for j in range(wp.static(width)):
            a[j] = x[g, j]
            scalar[g, j] = wp.exp(x[g, j])
        r = exp_of_lanes(a)
        for j in range(wp.static(width)):
            vector[g, j] = r[j]

    @wp.kernel(module="unique", enable_backward=False)
    def lanes_exp(x: wp.array2d(dtype=f64), out: wp.array2d(dtype=f64), reps: int):
        g = wp.tid()
        a = lanes()
        for j in range(wp.static(width)):
            a[j] = x[g, j]
        total = lanes()
        for _r in range(reps):
            total = total + exp_of_lanes(a)
            a = a + lanes(f64(1e-9))
        for j in range(wp.static(width)):
            out[g, j] = total[j]

    x = wp.array(np.random.default_rng(0).random((groups, width)) * 4.0 - 2.0, dtype=f64, device="cpu")
    ns = []
    for kernel in (scalar_exp, lanes_exp):
        out = wp.zeros((groups, width), dtype=f64, device="cpu")
        wp.launch(kernel, groups, inputs=[x, out, 1], device="cpu")
        walls = []
        for _ in range(repeats):
            start = time.perf_counter()
            wp.launch(kernel, groups, inputs=[x, out, reps], device="cpu")
            wp.synchronize()
            walls.append(time.perf_counter() - start)
        ns.append(min(walls) / (groups * width * reps) * 1e9)
    # one call each on 2^16 arguments across exp's useful range
    points = 8192
    wide = wp.array(np.linspace(-700.0, 700.0, points * width).reshape(points, width), dtype=f64, device="cpu")
    scalar = wp.zeros((points, width), dtype=f64, device="cpu")
    vector = wp.zeros((points, width), dtype=f64, device="cpu")
    wp.launch(one_call, points, inputs=[wide, scalar, vector], device="cpu")
    a, b = scalar.numpy(), vector.numpy()
    ulps = np.abs(a - b) / np.spacing(a)
    print(
        f"exp: wp.exp {ns[0]:.2f} ns, libmvec {width}-wide {ns[1]:.2f} ns ({ns[0] / ns[1]:.1f}x), best of {repeats}; "
        f"on {a.size} arguments in [-700, 700] the two differ by at most {ulps.max():.0f} ulp "
        f"({np.mean(ulps > 0):.1%} of them differ at all)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--strips", type=int, default=1024)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--lanes", type=int, nargs="+", default=[4, 8])
    parser.add_argument("--law", default="tagawa2003")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    wp.config.log_level = logging.WARNING
    wp.config.quiet = True
    wp.init()
    print(f"machine: {platform.processor() or platform.machine()}, {platform.system()}, warp {wp.__version__}, "
          f"one CPU thread, {args.strips} variants of the damped-swing sweep ({args.law}), turned and swinging, "
          f"{args.steps} steps of 2e-5 s")  # fmt: skip
    if any(args.strips % lanes for lanes in args.lanes):
        raise SystemExit(f"--strips {args.strips} must be a multiple of every --lanes {args.lanes}")
    overrides = [f"material.bending_law={args.law}", "integrator.dt_s=2e-5", f"sweep.random.samples={args.strips}"]
    scenes = wc.load_sweep("damped_swing_sweep", overrides).scenes
    # the sweep's variants, and the same without hysteresis (D1 = 0, the law's elastic limit)
    elastic = [s.to_dict() for s in scenes]
    for data in elastic:
        data["material"]["hysteresis_d1_gf_cm_per_cm"] = 0.0
    batches = {
        "law": build_batch(scenes, device="cpu"),
        "elastic": build_batch([wc.scene_from_dict(data) for data in elastic], device="cpu"),
    }
    batch = batches["law"]
    # each strip turned about its clamp edge by an angle of its own, so that it swings from
    # the start (segments keep their length; the clamp-edge hinge takes the kink)
    rest = batch.model.struct.rest_position.numpy()
    edge = batch.model.n_clamped - 1
    angle = np.random.default_rng(1).uniform(0.05, 0.5, args.strips)
    c, s_ = np.cos(angle), np.sin(angle)
    arm = rest[edge + 1 :] - rest[edge][None]
    bent = rest.copy()
    bent[edge + 1 :, :, 0] = rest[edge][None, :, 0] + c * arm[..., 0] - s_ * arm[..., 1]
    bent[edge + 1 :, :, 1] = rest[edge][None, :, 1] + s_ * arm[..., 0] + c * arm[..., 1]
    print(f"{'bending':>9} {'lanes':>5} {'per strip, strip-steps/s':>25} {'in lanes':>12} {'ratio':>6}  bitwise")
    for name, batch in batches.items():
        stepping = batch.solver.stepping(batch.control)
        for lanes in args.lanes:
            per_strip, in_lanes = kernels(lanes)
            states = [batch.model.state(), batch.model.state()]
            for state in states:
                state.set_positions(bent)
            runs = ((per_strip, args.strips), (in_lanes, args.strips // lanes))
            walls = [0.0, 0.0]
            for repeat in range(args.repeats + 1):  # the first compiles
                for k, (kernel, dim) in enumerate(runs):
                    start = time.perf_counter()
                    inputs = [batch.model.struct, stepping, states[k].struct, args.steps if repeat else 1]
                    wp.launch(kernel, dim=dim, inputs=inputs, device="cpu")
                    wp.synchronize()
                    walls[k] += (time.perf_counter() - start) if repeat else 0.0
            rates = [args.strips * args.steps * args.repeats / w for w in walls]
            same = all(
                np.array_equal(getattr(states[0].struct, field).numpy(), getattr(states[1].struct, field).numpy())
                for field in ("position", "velocity", "hinge")
            )
            print(f"{name:>9} {lanes:>5} {rates[0]:>25.3e} {rates[1]:>12.3e} {rates[1] / rates[0]:>5.2f}x  {same}")
    if exp_lanes.libmvec_loaded():
        for width in (4, 8):
            exp_timing(width)
    else:
        print("exp: no libmvec here (Linux x86-64 with glibc only): its vector exp not timed")


if __name__ == "__main__":
    main()
