"""Would strips in SIMD lanes speed up warpcloth's CPU step? (run by hand; issue 41)

    python benchmarks/cpu_lanes.py [--strips 1024] [--steps 1000] [--lanes 4 8] [--law tagawa2003]

The Numba port (benchmarks/numba_peer.py) runs strips as SIMD lanes; warpcloth's CPU
kernel gives each thread one strip. This measures, on the strip's real force pass (its
tension, hinge geometry and bending law, kernels/forces.py) and a node update, the same
hinge function called two ways in one process: one strip per thread walking its nodes,
and one group of L strips per thread with the lanes innermost, the layout a compiler can
vectorise ([node, strip] arrays hold a group's strips side by side). Both end bitwise the
same (checked). Each way runs with the hysteretic law and without it (elastic bending
only), which tells what a lane rewrite of the fused kernel could gain and what stands in
its way. One CPU thread; results in benchmarks/RESULTS.md.
"""

import argparse
import logging
import platform
import time

import numpy as np
import warp as wp
from warpcloth.kernels import geometry, integrators, structs, tensile
from warpcloth.kernels.status import STATUS_FOLDED, STATUS_OK, STATUS_STRAIN

import warpcloth as wc
from warpcloth.scene.build import build_batch

f64 = wp.float64
vec2 = wp.types.vector(2, f64)
zero, one = f64(0.0), f64(1.0)


def kernels(lanes: int, with_law: bool) -> tuple:
    """The per-strip and the lane kernel of one hinge function (``with_law``: the strip's
    law followed; else elastic bending alone)."""
    strip = structs.build(f64, ())
    StripModel, StripState, law = strip.StripModel, strip.StripState, strip.law
    Stepping = integrators.build(f64).Stepping
    tension = tensile.build(f64).force_per_width
    geo = geometry.build(f64)
    perp, signed_curvature = geo.perp, geo.signed_curvature

    @wp.func
    def hinge(model: StripModel, stepping: Stepping, state: StripState, s: int, i: int):
        # the body of forces.accumulate_internal_forces at node i, its first segment measured again
        first = model.n_clamped - 2
        l0 = model.rest_length
        node = state.position[i, s]
        e1 = node - state.position[i - 1, s]
        inverse_l1 = one / wp.length(e1)
        e2 = state.position[i + 1, s] - node
        l2 = wp.length(e2)
        inverse_l2 = one / l2
        strain = (l2 - l0) * (one / l0)
        code = STATUS_OK
        if not (wp.abs(strain) <= stepping.max_strain):
            code = STATUS_STRAIN
        f = tension(strain, model.tensile[s]) * model.width[s] * inverse_l2 * e2
        state.force_tensile[i, s] = state.force_tensile[i, s] + f
        state.force_tensile[i + 1, s] = vec2() - f
        h = i - first - 1
        curvature, chord = signed_curvature(e1, e2, inverse_l1, inverse_l2)
        if not (chord > f64(1e-3) * l0):
            code = STATUS_FOLDED
        if h == 0:
            curvature = curvature * model.edge_curvature_scale[s]
        curvature = curvature - model.rest_curvature[h, s]
        grip = model.grip[h, s]
        p = model.bending[s]
        width = model.width[s]
        tau_hysteretic = zero
        if wp.static(with_law):
            memory = law.follow(curvature, state.hinge[h, s], p, state.history, h, s)
            state.hinge[h, s] = memory
            tau_hysteretic = law.hysteretic_moment(curvature, memory, p) * grip[1] * width
        tau_elastic = law.elastic_moment(curvature, p) * grip[0] * width
        grad_i = perp(e1) * (inverse_l1 * inverse_l1)
        grad_k = perp(e2) * (inverse_l2 * inverse_l2)
        state.force_elastic[i - 1, s] = state.force_elastic[i - 1, s] - tau_elastic * grad_i
        state.force_elastic[i + 1, s] = vec2() - tau_elastic * grad_k
        state.force_elastic[i, s] = state.force_elastic[i, s] + tau_elastic * (grad_i + grad_k)
        state.force_hysteretic[i - 1, s] = state.force_hysteretic[i - 1, s] - tau_hysteretic * grad_i
        state.force_hysteretic[i + 1, s] = vec2() - tau_hysteretic * grad_k
        state.force_hysteretic[i, s] = state.force_hysteretic[i, s] + tau_hysteretic * (grad_i + grad_k)
        return code

    @wp.func
    def clear(state: StripState, s: int, i: int):
        state.force_tensile[i, s] = vec2()
        state.force_elastic[i, s] = vec2()
        state.force_hysteretic[i, s] = vec2()

    @wp.func
    def update(model: StripModel, state: StripState, s: int, i: int, dt: f64):
        # semi-implicit Euler under the internal forces and gravity (no drive: a timing probe)
        m = model.node_mass[s]
        f = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
        v = state.velocity[i, s] + (f + m * vec2(zero, -model.gravity)) * (dt / m)
        state.velocity[i, s] = v
        state.position[i, s] = state.position[i, s] + v * dt

    @wp.kernel(module="unique", enable_backward=False)
    def per_strip(model: StripModel, stepping: Stepping, state: StripState, steps: int):
        s = wp.tid()
        first = model.n_clamped - 2
        for _k in range(steps):
            clear(state, s, first)
            clear(state, s, first + 1)
            for i in range(first + 1, model.n_nodes - 1):
                if hinge(model, stepping, state, s, i) != STATUS_OK:
                    return
            for i in range(model.n_clamped, model.n_nodes - 1):
                update(model, state, s, i, stepping.dt)

    @wp.kernel(module="unique", enable_backward=False)
    def in_lanes(model: StripModel, stepping: Stepping, state: StripState, steps: int):
        g = wp.tid()
        first = model.n_clamped - 2
        for _k in range(steps):
            for j in range(wp.static(lanes)):
                clear(state, g * wp.static(lanes) + j, first)
                clear(state, g * wp.static(lanes) + j, first + 1)
            bad = int(0)  # noqa: UP018 (Warp: a variable the loop below reassigns)
            for i in range(first + 1, model.n_nodes - 1):
                for j in range(wp.static(lanes)):
                    bad = bad | hinge(model, stepping, state, g * wp.static(lanes) + j, i)
            if bad != 0:
                return
            for i in range(model.n_clamped, model.n_nodes - 1):
                for j in range(wp.static(lanes)):
                    update(model, state, g * wp.static(lanes) + j, i, stepping.dt)

    return per_strip, in_lanes


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
          f"one CPU thread, {args.strips} damped-swing strips ({args.law}), {args.steps} steps of 2e-5 s")  # fmt: skip
    scene = wc.load_scene("damped_swing", [f"material.bending_law={args.law}", "integrator.dt_s=2e-5"])
    batch = build_batch([scene] * args.strips, device="cpu")
    stepping = batch.solver.stepping(batch.control)
    print(f"{'bending':>9} {'lanes':>5} {'per strip, strip-steps/s':>25} {'in lanes':>12} {'ratio':>6}  bitwise")
    for with_law in (True, False):
        for lanes in args.lanes:
            per_strip, in_lanes = kernels(lanes, with_law)
            states = [batch.model.state(), batch.model.state()]
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
            same = np.array_equal(states[0].struct.position.numpy(), states[1].struct.position.numpy())
            name = "law" if with_law else "elastic"
            print(f"{name:>9} {lanes:>5} {rates[0]:>25.3e} {rates[1]:>12.3e} {rates[1] / rates[0]:>5.2f}x  {same}")


if __name__ == "__main__":
    main()
