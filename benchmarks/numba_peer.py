"""The strongest CPU peer a user could write: an expert Numba port of warpcloth's explicit
model, checked against warpcloth and timed beside it (issue 11, item 7; masing: issue 21).

    python benchmarks/numba_peer.py [--quick] [--samples 200] [--record 1.0]
        [--law tagawa2003|masing] [--parts agreement tables equal-accuracy]
        [--reference-dt 1e-6] [--check-dt 1e-7] [--tolerance 2e-3] [--repeats 3]
    python benchmarks/numba_peer.py --law masing --sweep-wall numba semi_implicit 4.9e-5

The port is the semi-implicit scheme of docs/model.md §2-§10 with either the paper's
hysteretic law (tagawa2003, parameters from ``MaterialSI.bending_parameters()``) or the
same loop with return-point memory (masing, §4.10), one law per batch; the second-order
clamp-edge hinge (``edge_curvature_scale``), mass-proportional damping, gravity, the half
mass at the free end and the whole hold-and-release of §8 (the free end carried along its
polar smootherstep path, held with the settle damping, released at t = 0). It handles the
fixed clamp only, which is what the damped swing and its sweep use, and skips the energy
budget warpcloth books every substep (which favours Numba). Every per-strip number
(masses, widths, tensile and bending parameters, damping, edge scale, hold target) and
the stepping (dt, release and move steps, output steps, the reversal memory's capacity) is
read from the batch warpcloth itself builds for the same scenes, so both run the same inputs.

How it is fast: strips are the innermost, contiguous axis ([node, strip]); a block of
LANES strips is copied into one local array whose inner dimensions are compile-time
constants, so LLVM can prove its loops over the lanes free of aliasing and vectorises them
(AVX-512: 8 float64 a register; AVX2: 4); ``numba.prange`` hands the blocks to the cores,
and each block runs every substep while its state stays in cache. The hinge does two
divisions (a reciprocal length per segment, the chord) as warpcloth's does since issue 11
item 5. The one transcendental per hinge and substep, the branch's exponential, is glibc's
libmvec exp (8-wide AVX-512 or 4-wide AVX2, whichever the CPU has) called directly
(Numba's LLVM from PyPI has no vector math library). tagawa2003 has no rare work: its
reversal keeps the offset by two selects (the gap to the asymptote, docs/model.md §4.3).
masing's runs only in the lanes that need it, in a scalar loop of its own: its reversal,
loop closure, full memory and first change, which is kernels/bending_masing.py's
``follow`` operation for operation on a per-lane stack of reversal points (capacity
``integrator.reversal_memory``; a reversal that finds it full is not stored, the hinge
retraces its branch, and it is counted, as in warpcloth). Between those events a masing
hinge stays on one branch H = H_r + a·(1 − exp(r·(K − K_r))) (the virgin curve is one
too), whose four numbers the scalar path leaves in the block array with the direction it
must keep and the curvature where it would close a loop: the common substep is the same
SIMD loop as tagawa2003's. No fastmath: reassociation would change the rounding and with
it the agreement with warpcloth below. Lengths are sqrt(fma(x, x, y·y)), as clang
contracts Warp's ``length``. Bitwise equality is not expected: libmvec's exp differs from
glibc's scalar exp (which Warp calls) in the last bit for ~40 % of arguments
(``--libm-exp`` uses the scalar one, 2× slower), and LLVM contracts Warp's C++ in places
Numba's IR does not. Compiled code is cached on disk (``cache=True``; ``--libm-exp``
compiles afresh), so a second process starts in about a second.

What it prints, all measured in this one run (compile time excluded: every code path is
run once before timing):
1. agreement (``--parts agreement``): the 200-variant damped-swing sweep
   (scenes/damped_swing_sweep.toml, its Latin hypercube of D, D1, α, γ; 1 s record after
   the 1.3 s hold) under ``--law``, warpcloth's tip trajectories (600 Hz probes) against
   the Numba port's, both from the straight hanging strip through the same hold and
   release; for masing also the deepest reversal stack and the overflows of both; and the
   sweep's wall at the scene dt, ``wc.run_sweep`` on 2 threads against the port on 2;
2. strip-steps/s and wall per simulated second for B = 1, 16, 200, 1024 strips
   (``--parts tables``): warpcloth on 1 thread (one launch) and 2 threads (two
   half-batches launched from two Python threads; Warp releases the GIL during a CPU
   launch), NumPy (benchmarks/numpy_baseline.py; tagawa2003 only), Numba on 1 and 2
   threads; ratios against warpcloth on 1 thread;
3. the sweep at equal accuracy (``--parts equal-accuracy``): every variant's largest
   |Δ tip x| over the record, as a fraction of its excursion, against the explicit
   solution at ``--reference-dt`` (computed by the port), for warpcloth semi_implicit,
   the port, warpcloth imex and imex_trapezoidal on ladders of dt that divide the probe
   interval; the largest dt of each whose worst variant is within ``--tolerance``; the
   variants worst under the implicit schemes rechecked against ``--check-dt``; then the
   sweep's wall at those dt (and
   warpcloth at the scene dt), repeats interleaved, with the ratio to the port's.
``--sweep-wall IMPL SCHEME DT`` times one sweep and nothing else, for timing the whole
process from outside (start-up and, for the port, loading its cached code included).
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import platform
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import llvmlite.binding as llvm
import numba
import numpy as np
import pandas as pd
import warp as wp
from llvmlite import ir
from numba import njit, prange, types
from numba.core import cgutils
from numba.core.caching import NullCache
from numba.extending import intrinsic

import warpcloth as wc
from warpcloth.scene import build_batch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from numpy_baseline import NumpyStrips, displaced_start  # noqa: E402


@intrinsic
def fma(typingctx, a, b, c):
    """a·b + c rounded once (llvm.fma), which Numba does not expose; it vectorises."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return sig, codegen


LIBMVEC_EXP = {8: "_ZGVeN8v_exp", 4: "_ZGVdN4v_exp"}  # glibc's AVX-512 and AVX2 exp, by width


def _libmvec() -> int:
    """Load glibc's vector math library; the width of the widest exp this CPU can run
    (8: AVX-512, 4: AVX2), 0 if none."""
    try:
        flags = Path("/proc/cpuinfo").read_text()
        width = 8 if " avx512f" in flags else 4 if " avx2" in flags else 0
        if width:
            llvm.load_library_permanently("libmvec.so.1")
        return width
    except (OSError, RuntimeError):
        return 0


# The branch's exponential is the one transcendental per hinge and substep. Numba's PyPI
# LLVM has no vector exp (no SVML), so a loop calling math.exp runs glibc's scalar exp,
# ~3 ns a call, about half of the whole substep. glibc's libmvec has an 8-wide AVX-512
# exp (0.7 ns an element, within 4 ulp; it differs from the scalar one in the last bit
# for ~40 % of arguments) and a 4-wide AVX2 one: called directly below (0: the scalar
# call, which --libm-exp selects).
VECTOR_EXP = _libmvec()


@intrinsic
def vector_exp(typingctx, array, start):
    """array[start : start + VECTOR_EXP] ← exp(…) in place, by libmvec (LIBMVEC_EXP)."""
    sig = types.void(array, start)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        vector = ir.VectorType(ir.DoubleType(), VECTOR_EXP)
        pointer = builder.bitcast(builder.gep(data, [args[1]]), vector.as_pointer())
        function = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(vector, [vector]), LIBMVEC_EXP[VECTOR_EXP]
        )
        builder.store(builder.call(function, [builder.load(pointer, align=8)]), pointer, align=8)
        return context.get_dummy_value()

    return sig, codegen


@njit(inline="always")
def norm(x, y):
    """|(x, y)| as Warp's compiled ``wp.length`` rounds it: sqrt(fma(x, x, y·y))."""
    return math.sqrt(fma(x, x, y * y))


@njit(error_model="numpy", cache=True)
def fresh_hinges(px, py, nc, edge_scale, law, masing, hinges, points):
    """Every hinge fresh at its current curvature (§4.5): tagawa2003 on the rising branch
    with no offset; masing at the origin of its virgin curve, ``points[strip, hinge, 0]``
    (the hinge planes are those of the block array, ``hinges[plane − HB, hinge, strip]``)."""
    n, b = px.shape
    for j in range(n - nc):
        i = nc - 1 + j
        for s in range(b):
            e1x, e1y = px[i, s] - px[i - 1, s], py[i, s] - py[i - 1, s]
            e2x, e2y = px[i + 1, s] - px[i, s], py[i + 1, s] - py[i, s]
            k = (
                2.0
                * (e1x * e2y - e1y * e2x)
                * (1.0 / norm(e1x, e1y))
                * (1.0 / norm(e2x, e2y))
                / norm(e1x + e2x, e1y + e2y)
            )
            if j == 0:
                k = k * edge_scale[s]
            d1, m0 = law[1, s], law[4, s]
            hinges[:, j, s] = 0.0
            hinges[HK - HB, j, s] = k
            if masing:
                # Depth 0, on the virgin curve at its origin: every direction loads, so the
                # first change takes the scalar path (TD = 0), which sets the branch.
                hinges[HB - HB, j, s], hinges[HC - HB, j, s] = 1.0, k
                if d1 != 0.0:
                    points[s, j, 0, 0], points[s, j, 0, 1] = k, 0.0
            else:  # rising, no offset: its gap to the rising asymptote is M0
                hinges[HB - HB, j, s], hinges[HC - HB, j, s] = 1.0, m0


@njit(inline="always")
def masing_open_point(points, slot, h, depth, origin):
    """The top open point (K, H) of a masing hinge (the origin (K_o, 0) at depth 0) and the
    curvature of the one below it (kernels/bending_masing.py ``open_point``)."""
    if depth == 0:
        return origin, 0.0, origin
    below = points[slot, h, depth - 1, 0] if depth > 1 else origin
    return points[slot, h, depth, 0], points[slot, h, depth, 1], below


@njit(error_model="numpy", cache=True)
def masing_follow(k, W, h, lane, points, overflows, deepest, slot, d1, alpha):
    """The scalar path of a masing hinge, rare (a reversal, a closed loop, the memory full
    or the first change): kernels/bending_masing.py ``follow`` operation for operation, its
    stack ``points[slot, h]``, then the branch the block's SIMD loop evaluates now (HC, TH,
    TA, TR) and the test that keeps the next evaluation off this path (TD, TT)."""
    previous = W[h, HK, lane]
    d = -1.0 if k - previous < 0.0 else 1.0
    last = -1.0 if W[h, HB, lane] < 0.0 else 1.0
    depth = int(abs(W[h, HB, lane])) - 1
    capacity = points.shape[2] - 1
    origin = points[slot, h, 0, 0]
    top_k, top_h, below = masing_open_point(points, slot, h, depth, origin)
    s = d  # on the virgin curve at its origin every direction loads
    if depth > 0:
        s = -1.0 if top_k > below else 1.0
    elif previous != origin:
        s = -1.0 if previous - origin < 0.0 else 1.0
    if d != s and last != d:
        # The curvature reversed at the previous evaluation, against the current branch.
        if depth < capacity:
            below = top_k
            depth += 1
            top_k, top_h = previous, W[h, HH, lane]
            points[slot, h, depth, 0], points[slot, h, depth, 1] = top_k, top_h
            s = d
            deepest[slot] = max(deepest[slot], depth)
        else:
            overflows[slot] += 1
    # Retracing after a reversal the full memory could not hold, until the top point.
    while d != s and depth > 0 and s * (k - top_k) <= 0.0:
        depth -= 1
        s = d
        top_k, top_h, below = masing_open_point(points, slot, h, depth, origin)
    # Return-point memory: reaching the point below the top closes the inner loop.
    while d == s and depth > 0:
        target = below if depth > 1 else 2.0 * origin - top_k
        if s * (k - target) < 0.0:
            break
        depth = max(depth - 2, 0)
        top_k, top_h, below = masing_open_point(points, slot, h, depth, origin)
    W[h, HB, lane] = d * float(depth + 1)
    if depth == 0:
        # virgin: sgn(y)·½D1·(1 − e^(−2α|y|)), y = K − K_o; −2α·sgn(y)·y = −2α|y| exactly
        v = -1.0 if k - origin < 0.0 else 1.0
        W[h, HC, lane], W[h, TH, lane] = origin, 0.0
        W[h, TA, lane], W[h, TR, lane] = v * 0.5 * d1, -2.0 * alpha * v
        # next: loading away from the origin, no loop to close
        nxt = 0.0 if k == origin else v
        W[h, TD, lane], W[h, TT, lane] = nxt, nxt * math.inf
    else:
        W[h, HC, lane], W[h, TH, lane] = top_k, top_h
        W[h, TA, lane], W[h, TR, lane] = s * d1, -alpha * s
        nxt = -1.0 if top_k > below else 1.0
        W[h, TD, lane] = nxt if nxt == s else 0.0
        W[h, TT, lane] = below if depth > 1 else 2.0 * origin - top_k


# A block's whole working set is ONE local array W[row, plane, lane] whose two inner
# dimensions are compile-time constants. LLVM then sees every access as one base pointer
# plus offsets that differ by constants, proves the loops over lanes free of aliasing and
# vectorises them with no runtime checks; with the arrays apart (Numba tells LLVM nothing
# about their aliasing) it needs a check per pair of arrays, gives up, and runs them
# scalar. Rows 0 … NMAX−1 are nodes (hinge h lives in row h), row NMAX holds the per-lane
# temporaries, row NMAX + 1 the per-strip parameters.
LANES = 16  # two AVX-512 registers of float64 (LLVM treats loops under 16 trips as tiny: scalar)
NMAX = 64  # most nodes a strip may have (h = 2.5 mm has 49)
X, Y, U, V, FTX, FTY, FEX, FEY, FHX, FHY = range(10)  # node planes
# Hinge planes. tagawa2003: branch s, gap g = M0 − s H to its asymptote, K_prev, H. masing: the signed depth
# d·(depth + 1) of warpcloth's memory vector, the top reversal point's curvature, K_prev, H,
# then the branch this evaluation is on, H = TH + TA·(1 − exp(TR·(K − HC))) (the virgin
# curve from the origin too), and what lets the next evaluation stay on it: the direction
# TD it must keep (0: take the scalar path) and the curvature TT where it would close a
# loop (docs/model.md §4.10, kernels/bending_masing.py).
HB, HC, HK, HH, TH, TA, TR, TD, TT = range(10, 19)
HINGE_PLANES = 9  # hinge planes HB … TT, kept between runs as hinges[plane, hinge, strip]
E1X, E1Y, IL1, E2X, E2Y, IL2, KK, EX, BAD, R0, R1, A0, TURN, SCALAR = range(14)  # row NMAX
A1, A2, A3, A4, RIGIDITY, D1, ALPHA, K0, M0, WIDTH, SCALE, MASS, GAMMA, SETTLE = range(14)  # row NMAX + 1
PLANES = 19


@njit(error_model="numpy", cache=True)
def advance_block(
    s0,
    s1,
    step0,
    step1,
    out_steps,
    px,
    py,
    vx,
    vy,
    masing,
    hinges,
    points,
    overflows,
    deepest,
    tensile,
    law,
    width,
    node_mass,
    gamma,
    settle_gamma,
    edge_scale,
    hold,
    nc,
    l0,
    gravity,
    dt,
    max_strain,
    release_step,
    move_steps,
    tip_x,
    tip_y,
    failed,
):
    """Strips s0 … s1−1 (at most LANES) from step0 to step1 (semi-implicit Euler,
    docs/model.md §9.1), in the block array W described above.

    Node indices are cast to unsigned (``np.uintp``) so Numba emits no wrap-around test
    for negative indices, which would hide from LLVM that rows i−1, i, i+1 are adjacent.
    ``tip_x/tip_y[k, s]`` take the free end after output step ``out_steps[k]``;
    ``failed[s]`` the first step whose strain or fold check failed (−1: healthy).
    ``masing`` selects the bending law (tagawa2003 otherwise); a masing lane keeps its
    reversal points in ``points[s0 + lane]``, the lanes past the last strip included (they
    copy it, and run its scalar path with it, so they never take that path on their own).
    """
    n = px.shape[0]
    used = s1 - s0
    first = nc - 2  # the clamped node above the clamp-edge hinge
    W = np.zeros((NMAX + 2, PLANES, LANES))
    T, P = np.uintp(NMAX), np.uintp(NMAX + 1)
    flat = W.reshape(W.size)  # the same memory, for vector_exp
    exp_row = (NMAX * PLANES + EX) * LANES
    for lane in range(LANES):
        s = s0 + min(lane, used - 1)
        for i in range(n):
            ii = np.uintp(i)
            W[ii, X, lane], W[ii, Y, lane], W[ii, U, lane], W[ii, V, lane] = px[i, s], py[i, s], vx[i, s], vy[i, s]
        for h in range(n - nc):
            for q in range(HINGE_PLANES):
                W[np.uintp(h), HB + q, lane] = hinges[q, h, s]
        if masing and lane >= used:
            points[s0 + lane] = points[s]
        W[P, A1, lane], W[P, A2, lane], W[P, A3, lane], W[P, A4, lane] = (
            tensile[0, s],
            tensile[1, s],
            tensile[2, s],
            tensile[3, s],
        )
        W[P, RIGIDITY, lane], W[P, D1, lane], W[P, ALPHA, lane] = law[0, s], law[1, s], law[2, s]
        W[P, K0, lane], W[P, M0, lane], W[P, WIDTH, lane], W[P, SCALE, lane] = (
            law[3, s],
            law[4, s],
            width[s],
            edge_scale[s],
        )
        W[P, MASS, lane], W[P, GAMMA, lane], W[P, SETTLE, lane] = node_mass[s], gamma[s], settle_gamma[s]
        # The held end's polar path (§8) is fixed per strip: its ends once, with the
        # operations warpcloth's carried_free_end takes at every step of the carry (and once,
        # for the end it holds, in reach_hold): the same values.
        sx, sy = hold[2, s] - hold[0, s], hold[3, s] - hold[1, s]
        gx, gy = hold[4, s] - hold[0, s], hold[5, s] - hold[1, s]
        W[T, R0, lane], W[T, R1, lane] = norm(sx, sy), norm(gx, gy)
        W[T, A0, lane] = math.atan2(sy, sx)
        t = math.atan2(gy, gx) - W[T, A0, lane]
        if t > math.pi:
            t = t - 2.0 * math.pi
        elif t < -math.pi:
            t = t + 2.0 * math.pi
        W[T, TURN, lane] = t
    rootx, rooty = hold[0, s0], hold[1, s0]
    il0 = 1.0 / l0
    tip = np.uintp(n - 1)
    k_out = 0
    while k_out < out_steps.shape[0] and out_steps[k_out] < step0:
        k_out += 1
    if k_out < out_steps.shape[0] and out_steps[k_out] == step0:
        for lane in range(used):
            tip_x[k_out, s0 + lane], tip_y[k_out, s0 + lane] = W[tip, X, lane], W[tip, Y, lane]
        k_out += 1
    for step in range(step0, step1):
        # ---- internal forces at x^n, one pass down the chain (kernels/forces.py) ----
        for i in range(first, first + 2):
            ii = np.uintp(i)
            for lane in range(LANES):
                W[ii, FTX, lane] = W[ii, FTY, lane] = W[ii, FEX, lane] = 0.0
                W[ii, FEY, lane] = W[ii, FHX, lane] = W[ii, FHY, lane] = 0.0
        a, b = np.uintp(first), np.uintp(first + 1)
        for lane in range(LANES):
            W[T, E1X, lane] = W[b, X, lane] - W[a, X, lane]
            W[T, E1Y, lane] = W[b, Y, lane] - W[a, Y, lane]
            W[T, IL1, lane] = 1.0 / norm(W[T, E1X, lane], W[T, E1Y, lane])
        for i in range(first + 1, n - 1):
            im, ii, ip = np.uintp(i - 1), np.uintp(i), np.uintp(i + 1)
            h = np.uintp(i - first - 1)
            # SIMD loop 1: tension of segment i, curvature at hinge i, the reversal test.
            # Divisions are the slowest SIMD operation: one per segment (its reciprocal
            # length, used by strain, tension, curvature and the angle gradient) and one
            # per hinge (the chord), as in warpcloth's hinge of issue 11 item 5.
            for lane in range(LANES):
                dx = W[ip, X, lane] - W[ii, X, lane]
                dy = W[ip, Y, lane] - W[ii, Y, lane]
                l2 = norm(dx, dy)
                r2 = 1.0 / l2
                strain = (l2 - l0) * il0
                e = abs(strain)
                t = e * (W[P, A1, lane] + e * (W[P, A2, lane] + e * (W[P, A3, lane] + e * W[P, A4, lane])))
                t = t if not strain < 0.0 else -t  # wp.sign: −1 below 0, else +1
                c = t * W[P, WIDTH, lane] * r2
                fx, fy = c * dx, c * dy
                W[ii, FTX, lane] += fx
                W[ii, FTY, lane] += fy
                W[ip, FTX, lane] = 0.0 - fx
                W[ip, FTY, lane] = 0.0 - fy
                e1x, e1y = W[T, E1X, lane], W[T, E1Y, lane]
                chord = norm(e1x + dx, e1y + dy)
                k = 2.0 * (e1x * dy - e1y * dx) * W[T, IL1, lane] * r2 / chord
                k = k * W[P, SCALE, lane] if i == first + 1 else k  # the clamp-edge hinge: §5.3
                W[T, KK, lane] = k
                W[T, E2X, lane], W[T, E2Y, lane], W[T, IL2, lane] = dx, dy, r2
                healthy = (e <= max_strain) & (chord > 1e-3 * l0)  # False for NaN too
                W[T, BAD, lane] = W[T, BAD, lane] if healthy else 1.0
            # The law, in loops of its own (selected per hinge, outside the lane loops, so
            # each stays a SIMD loop): which lanes need the scalar path, that path, and the
            # argument of the branch's exponential.
            rare = 0  # an integer OR: a float sum would not vectorise without fastmath
            if masing:
                # Scalar path unless the curvature is unchanged, the strip has no hysteresis,
                # or it keeps the branch's direction short of closing a loop.
                for lane in range(LANES):
                    k, td = W[T, KK, lane], W[h, TD, lane]
                    change = k - W[h, HK, lane]
                    d = -1.0 if change < 0.0 else 1.0
                    stays = (change == 0.0) | (W[P, D1, lane] == 0.0) | ((d == td) & (td * (k - W[h, TT, lane]) < 0.0))
                    W[T, SCALAR, lane] = 0.0 if stays else 1.0
                    rare |= 0 if stays else 1
                if rare:
                    for lane in range(LANES):
                        if W[T, SCALAR, lane] != 0.0:
                            masing_follow(
                                W[T, KK, lane],
                                W,
                                h,
                                lane,
                                points,
                                overflows,
                                deepest,
                                s0 + lane,
                                W[P, D1, lane],
                                W[P, ALPHA, lane],
                            )
                for lane in range(LANES):
                    W[T, EX, lane] = W[h, TR, lane] * (W[T, KK, lane] - W[h, HC, lane])
            else:
                # A lane whose curvature turned against its branch flips it and keeps its
                # offset: the gap to the new asymptote is 2 M0 − g (§4.3). No transcendental,
                # so the reversal is selects in the SIMD loop, as the kernel's is.
                for lane in range(LANES):
                    change = W[T, KK, lane] - W[h, HK, lane]
                    hb = W[h, HB, lane]
                    turn = change * hb < 0.0
                    hb = -hb if turn else hb
                    W[h, HB, lane] = hb
                    W[h, HC, lane] = 2.0 * W[P, M0, lane] - W[h, HC, lane] if turn else W[h, HC, lane]
                    W[T, EX, lane] = -W[P, ALPHA, lane] * hb * change
            # The branch's exponential (§4.2, §4.10), alone in its loop (see VECTOR_EXP).
            if VECTOR_EXP:
                for j in range(0, LANES, VECTOR_EXP):
                    vector_exp(flat, exp_row + j)
            else:
                for lane in range(LANES):
                    W[T, EX, lane] = math.exp(W[T, EX, lane])
            # The hysteretic moment H from the exponential; K becomes K_prev.
            if masing:
                for lane in range(LANES):
                    k = W[T, KK, lane]
                    change = k - W[h, HK, lane]
                    branch_h = W[h, TH, lane] + W[h, TA, lane] * (1.0 - W[T, EX, lane])
                    W[h, HH, lane] = W[h, HH, lane] if change == 0.0 else branch_h
                    depth1 = abs(W[h, HB, lane])  # the depth + 1, signed by the last change
                    W[h, HB, lane] = W[h, HB, lane] if change == 0.0 else (depth1 if change >= 0.0 else -depth1)
                    W[h, HK, lane] = k
            else:
                for lane in range(LANES):
                    # the kernel skips the exponential without hysteresis or change: the
                    # same bits (g = 0 there, or exp(0) = 1)
                    gap = W[h, HC, lane] * W[T, EX, lane]
                    W[h, HC, lane] = gap
                    W[h, HH, lane] = W[h, HB, lane] * (W[P, M0, lane] - gap)
                    W[h, HK, lane] = W[T, KK, lane]
            # SIMD loop 2: the hinge's forces on nodes i−1, i, i+1 (§5.1).
            for lane in range(LANES):
                k, ho = W[T, KK, lane], W[h, HH, lane]
                q1 = W[T, IL1, lane] * W[T, IL1, lane]
                q2 = W[T, IL2, lane] * W[T, IL2, lane]
                gix, giy = -W[T, E1Y, lane] * q1, W[T, E1X, lane] * q1
                gkx, gky = -W[T, E2Y, lane] * q2, W[T, E2X, lane] * q2
                te = W[P, RIGIDITY, lane] * k * W[P, WIDTH, lane]
                th = ho * W[P, WIDTH, lane]
                W[im, FEX, lane] = W[im, FEX, lane] - te * gix
                W[im, FEY, lane] = W[im, FEY, lane] - te * giy
                W[ip, FEX, lane] = 0.0 - te * gkx
                W[ip, FEY, lane] = 0.0 - te * gky
                W[ii, FEX, lane] = W[ii, FEX, lane] + te * (gix + gkx)
                W[ii, FEY, lane] = W[ii, FEY, lane] + te * (giy + gky)
                W[im, FHX, lane] = W[im, FHX, lane] - th * gix
                W[im, FHY, lane] = W[im, FHY, lane] - th * giy
                W[ip, FHX, lane] = 0.0 - th * gkx
                W[ip, FHY, lane] = 0.0 - th * gky
                W[ii, FHX, lane] = W[ii, FHX, lane] + th * (gix + gkx)
                W[ii, FHY, lane] = W[ii, FHY, lane] + th * (giy + gky)
                W[T, E1X, lane], W[T, E1Y, lane], W[T, IL1, lane] = W[T, E2X, lane], W[T, E2Y, lane], W[T, IL2, lane]
        # ---- free nodes: damping, gravity, semi-implicit Euler (kernels/strip.py) ----
        held = step < release_step
        last = n - 1 if held else n
        for i in range(nc, last):
            ii = np.uintp(i)
            half = 0.5 if i == n - 1 else 1.0  # the free end carries half a node's mass
            for lane in range(LANES):
                m = half * W[P, MASS, lane]
                g = W[P, SETTLE, lane] if held else W[P, GAMMA, lane]
                fx = W[ii, FTX, lane] + W[ii, FEX, lane] + W[ii, FHX, lane]
                fy = W[ii, FTY, lane] + W[ii, FEY, lane] + W[ii, FHY, lane]
                fx = fx + -g * m * W[ii, U, lane] + m * 0.0
                fy = fy + -g * m * W[ii, V, lane] + m * -gravity
                # half the first kick of a node that starts moving (kernels/integrators.py kick_mass)
                w = dt / (2.0 * m) if step == 0 or (i == n - 1 and step == release_step) else dt / m
                un = W[ii, U, lane] + fx * w
                vn = W[ii, V, lane] + fy * w
                W[ii, X, lane] = W[ii, X, lane] + un * dt
                W[ii, Y, lane] = W[ii, Y, lane] + vn * dt
                W[ii, U, lane], W[ii, V, lane] = un, vn
        if held:
            # The held free end on its path at level step + 1 (kernels/drives.py).
            p, dp = 1.0, 0.0
            if step + 1 < move_steps:
                xs = float(step + 1) / float(move_steps)
                p = xs * xs * xs * (xs * (xs * 6.0 - 15.0) + 10.0)
                dp = 30.0 * xs * xs * (xs - 1.0) * (xs - 1.0) / (float(move_steps) * dt)
            for lane in range(LANES):
                r0, r1 = W[T, R0, lane], W[T, R1, lane]
                r = r0 + (r1 - r0) * p
                a = W[T, A0, lane] + W[T, TURN, lane] * p
                cx, cy = math.cos(a), math.sin(a)
                W[tip, X, lane], W[tip, Y, lane] = rootx + r * cx, rooty + r * cy
                rt = r * W[T, TURN, lane]
                W[tip, U, lane] = dp * ((r1 - r0) * cx + rt * -cy)
                W[tip, V, lane] = dp * ((r1 - r0) * cy + rt * cx)
        if k_out < out_steps.shape[0] and out_steps[k_out] == step + 1:
            for lane in range(used):
                tip_x[k_out, s0 + lane], tip_y[k_out, s0 + lane] = W[tip, X, lane], W[tip, Y, lane]
            k_out += 1
        for lane in range(used):
            if W[T, BAD, lane] != 0.0 and failed[s0 + lane] < 0:
                failed[s0 + lane] = step
    for lane in range(used):
        s = s0 + lane
        for i in range(n):
            ii = np.uintp(i)
            px[i, s], py[i, s], vx[i, s], vy[i, s] = W[ii, X, lane], W[ii, Y, lane], W[ii, U, lane], W[ii, V, lane]
        for h in range(n - nc):
            for q in range(HINGE_PLANES):
                hinges[q, h, s] = W[np.uintp(h), HB + q, lane]


@njit(parallel=True, error_model="numpy", cache=True)
def advance(
    blocks,
    step0,
    step1,
    out_steps,
    px,
    py,
    vx,
    vy,
    masing,
    hinges,
    points,
    overflows,
    deepest,
    tensile,
    law,
    width,
    node_mass,
    gamma,
    settle_gamma,
    edge_scale,
    hold,
    nc,
    l0,
    gravity,
    dt,
    max_strain,
    release_step,
    move_steps,
    tip_x,
    tip_y,
    failed,
):
    """Every block of strips (``blocks[b]`` … ``blocks[b + 1]``) on the cores: prange."""
    for b in prange(blocks.shape[0] - 1):
        advance_block(
            blocks[b],
            blocks[b + 1],
            step0,
            step1,
            out_steps,
            px,
            py,
            vx,
            vy,
            masing,
            hinges,
            points,
            overflows,
            deepest,
            tensile,
            law,
            width,
            node_mass,
            gamma,
            settle_gamma,
            edge_scale,
            hold,
            nc,
            l0,
            gravity,
            dt,
            max_strain,
            release_step,
            move_steps,
            tip_x,
            tip_y,
            failed,
        )


class NumbaStrips:
    """A batch of scenes as the Numba port runs them, its inputs read from warpcloth's own
    batch of the same scenes (so both get bitwise the same parameters)."""

    def __init__(self, scenes: list[wc.Scene], initial_positions: np.ndarray | None = None) -> None:
        batch = build_batch(scenes)
        model, control, solver, recorder = batch.model, batch.control, batch.solver, batch.recorder
        laws = {s.material.bending_law for s in model.strips}
        if len(laws) != 1 or not laws <= {"tagawa2003", "masing"}:
            raise ValueError(f"the Numba peer implements one of tagawa2003 and masing per batch, not {sorted(laws)}")
        self.masing = laws == {"masing"}
        if any(len(s.clamp.start) for s in model.strips) or model.precision != "float64":
            raise ValueError("the Numba peer implements the fixed clamp in float64 only")
        if solver.scheme != "semi_implicit":
            raise ValueError("the Numba peer implements integrator.scheme = semi_implicit only")
        b, n = model.n_strips, model.n_nodes
        self.n_strips, self.nc, self.l0, self.gravity = b, model.n_clamped, model.spacing, model.gravity
        self.dt, self.max_strain = solver.dt, solver.divergence_strain
        self.release_step = solver.release_step(control)
        self.move_steps = max(1, solver.step_of(control.move_time))
        self.out_steps = recorder.schedule(control, solver).steps.astype(np.int64)
        self.kept = len(recorder.schedule(control, solver).kept)
        self.tensile = np.ascontiguousarray(model.tensile.T)
        self.law = np.ascontiguousarray(model.bending.T)
        self.width, self.node_mass = model.width.copy(), model.node_mass.copy()
        self.gamma = model.damping.copy()
        self.settle_gamma = np.array([s.settle_damping for s in model.strips])
        self.edge_scale = model.edge_curvature_scale.copy()
        rest = model.rest_positions
        self.hold = np.empty((6, b))
        self.hold[0:2] = rest[self.nc - 1][:, None]  # the clamp edge: root of the held end's path
        self.hold[2:4] = rest[n - 1][:, None]
        self.hold[4:6] = control.hold_target.T
        x = np.repeat(rest[:, None, :], b, axis=1) if initial_positions is None else initial_positions
        self.px, self.py = np.ascontiguousarray(x[..., 0]), np.ascontiguousarray(x[..., 1])
        self.vx, self.vy = np.zeros((n, b)), np.zeros((n, b))
        hinges = n - self.nc
        self.hinges = np.empty((HINGE_PLANES, hinges, b))
        # masing: every lane of every block has a stack (the last block's spare lanes too)
        lanes = -(-b // LANES) * LANES
        self.capacity = model.reversal_memory
        self.points = np.zeros((lanes, hinges, self.capacity + 1, 2) if self.masing else (1, 1, 1, 2))
        self.overflows, self.deepest = np.zeros(lanes, dtype=np.int64), np.zeros(lanes, dtype=np.int64)
        fresh_hinges(self.px, self.py, self.nc, self.edge_scale, self.law, self.masing, self.hinges, self.points)
        self.step = 0
        self.tip_x = np.full((len(self.out_steps), b), np.nan)
        self.tip_y = np.full((len(self.out_steps), b), np.nan)
        self.failed = np.full(b, -1, dtype=np.int64)

    def blocks(self, threads: int) -> np.ndarray:
        """Block boundaries: LANES strips each (the last may be short); ``threads`` is
        unused, prange deals the blocks to the threads."""
        return np.append(np.arange(0, self.n_strips, LANES), self.n_strips).astype(np.int64)

    def run(self, steps: int | None = None) -> None:
        """Advance ``steps`` substeps (default: to the last output step)."""
        end = int(self.out_steps[-1]) if steps is None else self.step + steps
        advance(
            self.blocks(numba.get_num_threads()),
            self.step,
            end,
            self.out_steps,
            self.px,
            self.py,
            self.vx,
            self.vy,
            self.masing,
            self.hinges,
            self.points,
            self.overflows,
            self.deepest,
            self.tensile,
            self.law,
            self.width,
            self.node_mass,
            self.gamma,
            self.settle_gamma,
            self.edge_scale,
            self.hold,
            self.nc,
            self.l0,
            self.gravity,
            self.dt,
            self.max_strain,
            self.release_step,
            self.move_steps,
            self.tip_x,
            self.tip_y,
            self.failed,
        )
        self.step = end

    def kept_tips(self) -> tuple[np.ndarray, np.ndarray]:
        """Tip x and y ``[sample, strip]`` at the recorded samples t ≥ 0."""
        first = len(self.out_steps) - self.kept
        return self.tip_x[first:], self.tip_y[first:]


def sweep_scenes(samples: int, record: float, overrides: list[str] = ()) -> tuple[object, list[wc.Scene]]:
    """The bundled damped-swing sweep cut to ``samples`` variants and a ``record`` s record."""
    sweep = wc.load_sweep(
        "damped_swing_sweep", [f"sweep.random.samples={samples}", f"run.duration_s={record}", *overrides]
    )
    return sweep, list(sweep.scenes)


def free_runs(samples: int, duration: float, count: int, extra: list[str] = ()) -> list[wc.Scene]:
    """``count`` sweep variants (cycled) without the hold, for the throughput tables
    (``extra``: more overrides, e.g. the scheme and dt)."""
    _sweep, scenes = sweep_scenes(samples, duration, ["release.enabled=false", *extra])
    return [scenes[i % len(scenes)] for i in range(count)]


def warpcloth_wall(scenes: list[wc.Scene], x0: np.ndarray, threads: int) -> tuple[float, int]:
    """Wall seconds and strip-steps of warpcloth on ``scenes`` from ``x0``: one launch
    sequence, or the batch split in ``threads`` parts launched from as many Python threads."""
    parts = [list(range(len(scenes)))[t::threads] for t in range(threads)]
    parts = [p for p in parts if p]
    done = []

    def one(part: list[int]) -> None:
        # one launch a Python thread: the threads here are the ones being measured
        result = wc.simulate(
            [scenes[i] for i in part],
            initial_positions=np.repeat(x0[:, None, :], len(part), axis=1),
            keep_frames=False,
            on_divergence="record",
            threads=1,
        )
        done.append(result.strip_steps)

    start = time.perf_counter()
    workers = [threading.Thread(target=one, args=(p,)) for p in parts]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    return time.perf_counter() - start, sum(done)


def warpcloth_rate(
    samples: int, b: int, steps: int, dt: float, x0: np.ndarray, threads: int, extra: list[str] = ()
) -> float:
    """warpcloth's stepping rate (strip-steps/s) on ``b`` strips: the wall of a run of
    about ``steps`` steps less that of a one-sample run, so building the batch (about
    0.1 ms a strip, in the sweep's wall below) is left out as it is for the others. The
    long run is at least ten samples: with two (``--quick`` at 1024 strips) the
    difference was one sample's steps against the batch's build, and its noise gave
    negative rates. NaN (printed —) when the difference is still within the noise."""
    interval = free_runs(samples, 1.0, 1, extra)[0].output_interval
    long_wall, long_steps = warpcloth_wall(
        free_runs(samples, max(10, round(steps * dt / interval)) * interval, b, extra), x0, threads
    )
    short_wall, short_steps = warpcloth_wall(free_runs(samples, interval, b, extra), x0, threads)
    if long_wall < 2.0 * short_wall:
        return math.nan
    return (long_steps - short_steps) / (long_wall - short_wall)


def machine() -> str:
    """The CPU as lscpu names it, with its core count."""
    try:
        info = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        name = next(line.split(":", 1)[1].strip() for line in info.splitlines() if line.startswith("Model name"))
    except (OSError, subprocess.CalledProcessError, StopIteration):
        name = platform.processor() or platform.machine()
    return f"{name}, {os.cpu_count()} cores"


def agreement(sweep_dir: Path, peer: NumbaStrips) -> tuple[float, float]:
    """Largest tip-position gap (m) between warpcloth's sweep probes and the peer's, over
    every variant and sample, and the largest tip excursion (m) for scale."""
    probes = pd.read_parquet(sweep_dir / "probes").sort_values(["variant", "t"])
    tx, ty = peer.kept_tips()
    gap, excursion = 0.0, 0.0
    for variant, rows in probes.groupby("variant"):
        wx, wy = rows["tip_x"].to_numpy(), rows["tip_y"].to_numpy()
        if len(wx) != tx.shape[0]:
            return math.inf, math.nan
        gap = max(gap, np.abs(wx - tx[:, variant]).max(), np.abs(wy - ty[:, variant]).max())
        excursion = max(excursion, np.abs(wx).max())
    return gap, excursion


def tip_errors(tips: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Each variant's largest |Δ tip x| over the record as a fraction of its reference
    excursion (``[sample, variant]`` arrays; the metric of benchmarks/imex_defaults.py)."""
    if tips.shape != reference.shape:
        return np.full(reference.shape[1], math.inf)
    return np.abs(tips - reference).max(axis=0) / np.ptp(reference, axis=0)


def warpcloth_tips(scenes: list[wc.Scene]) -> tuple[np.ndarray, str]:
    """Tip x ``[sample, variant]`` of warpcloth on 2 threads (inf where a strip diverged)
    and what its reversal memory held."""
    result = wc.simulate(scenes, keep_frames=False, on_divergence="record", threads=2)
    tips = result.probe("tip_x").copy()
    tips[:, [d.strip for d in result.diverged]] = math.inf
    memory = result.reversal_memory
    held = (
        (f"; deepest {np.max(memory['deepest'])} of {memory['capacity']}, {np.sum(memory['overflows'])} overflows")
        if memory
        else ""
    )
    return tips, held


def numba_tips(scenes: list[wc.Scene]) -> tuple[np.ndarray, str]:
    """Tip x ``[sample, variant]`` of the Numba port on 2 threads (inf where a strip failed)
    and what its reversal memory held."""
    numba.set_num_threads(2)
    peer = NumbaStrips(scenes)
    peer.run()
    tips = peer.kept_tips()[0].copy()
    tips[:, peer.failed >= 0] = math.inf
    b = peer.n_strips
    held = (
        f"; deepest {peer.deepest[:b].max()} of {peer.capacity}, {peer.overflows[:b].sum()} overflows"
        if peer.masing
        else ""
    )
    return tips, held


def stepping(scheme: str, dt: float) -> list[str]:
    """The overrides for ``scheme`` at ``dt``."""
    return [f'integrator.scheme="{scheme}"', f"integrator.dt_s={dt!r}"]


def sweep_wall(impl: str, samples: int, record: float, overrides: list[str]) -> float:
    """Wall seconds of the sweep: ``wc.run_sweep(workers=2)`` into a fresh directory
    (building the batches and writing the sweep included), or the Numba port on 2 threads
    (building warpcloth's batch for its inputs included, no files)."""
    sweep, scenes = sweep_scenes(samples, record, overrides)
    start = time.perf_counter()
    if impl == "warpcloth":
        with tempfile.TemporaryDirectory() as tmp:
            wc.run_sweep(sweep, Path(tmp) / "sweep", workers=2)
            return time.perf_counter() - start
    numba.set_num_threads(2)
    NumbaStrips(scenes).run()
    return time.perf_counter() - start


def equal_accuracy(args: argparse.Namespace, law: list[str], samples: int) -> None:
    """The sweep at equal accuracy: each candidate's worst variant against the explicit
    reference at ``--reference-dt`` (computed by the port, which agrees with warpcloth to
    rounding, part 1), the largest dt of each within ``--tolerance``, then the walls."""
    record = args.record
    print(
        f"\n---- equal accuracy on the {samples}-variant sweep ({' '.join(law) or 'tagawa2003'}; "
        f"{record:g} s record; tolerance {args.tolerance:.2%} of each variant's excursion, worst variant) ----"
    )
    start = time.perf_counter()
    reference, _held = numba_tips(
        sweep_scenes(samples, record, [*law, *stepping("semi_implicit", args.reference_dt)])[1]
    )
    print(
        f"reference: semi_implicit dt = {args.reference_dt:g} s by the Numba port, "
        f"{time.perf_counter() - start:.0f} s wall"
    )
    scene_dt = sweep_scenes(1, record, law)[1][0].integrator.dt_s
    ladders = {
        ("warpcloth", "semi_implicit"): args.explicit_ladder,
        ("numba", "semi_implicit"): args.explicit_ladder,
        ("warpcloth", "imex"): args.imex_ladder,
        ("warpcloth", "imex_trapezoidal"): args.imex_ladder,
    }
    best: dict[tuple[str, str], float] = {}
    tips: dict[tuple[str, str, float], np.ndarray] = {}
    for (impl, scheme), ladder in ladders.items():
        for dt in ladder:
            try:
                scenes = sweep_scenes(samples, record, [*law, *stepping(scheme, dt)])[1]
            except wc.SceneError as error:
                print(f"  {impl:>9} {scheme:>13} dt = {dt:8.3g} s: refused ({error})")
                break
            tips[impl, scheme, dt], held = (warpcloth_tips if impl == "warpcloth" else numba_tips)(scenes)
            errors = tip_errors(tips[impl, scheme, dt], reference)
            worst = int(np.argmax(errors))
            print(
                f"  {impl:>9} {scheme:>16} dt = {dt:8.3g} s: worst {errors[worst]:.3%} (variant {worst}), "
                f"median {np.median(errors):.3%}{held}"
            )
            if errors[worst] <= args.tolerance:
                best[impl, scheme] = dt
    print("largest dt within the tolerance: " + ", ".join(f"{i} {s} {dt:g} s" for (i, s), dt in best.items()))
    for dt in args.explicit_ladder:
        if ("warpcloth", "semi_implicit", dt) in tips and ("numba", "semi_implicit", dt) in tips:
            gap = np.abs(tips["warpcloth", "semi_implicit", dt] - tips["numba", "semi_implicit", dt]).max()
            print(f"  warpcloth against the port, semi_implicit at dt = {dt:.4g} s: largest tip x gap {gap:.2e} m")
    implicit = [scheme for scheme in ("imex", "imex_trapezoidal") if ("warpcloth", scheme) in best]
    if args.check_dt and implicit:
        # The reference's own error: the variants worst at the chosen implicit steps, again
        # against a finer explicit solution.
        worst = np.unique(
            np.concatenate(
                [
                    np.argsort(tip_errors(tips["warpcloth", scheme, best["warpcloth", scheme]], reference))[
                        -args.check_worst :
                    ]
                    for scheme in implicit
                ]
            )
        )
        start = time.perf_counter()
        finer_scenes = sweep_scenes(samples, record, [*law, *stepping("semi_implicit", args.check_dt)])[1]
        finer, _held = numba_tips([finer_scenes[i] for i in worst])
        print(
            f"check: the {len(worst)} variants worst under {' and '.join(implicit)} at their steps against "
            f"semi_implicit dt = {args.check_dt:g} s ({time.perf_counter() - start:.0f} s wall); the reference "
            f"is off it by {tip_errors(reference[:, worst], finer).max():.4%} at most"
        )
        for (impl, scheme, dt), run in tips.items():
            print(
                f"  {impl:>9} {scheme:>16} dt = {dt:8.3g} s: worst of these "
                f"{tip_errors(run[:, worst], finer).max():.3%}"
            )
    runs = [("warpcloth", "semi_implicit", scene_dt)] + [(i, s, dt) for (i, s), dt in best.items()]
    walls: dict[tuple[str, str, float], list[float]] = {run: [] for run in runs}
    loads = []
    for _ in range(args.repeats):
        for run in runs:  # interleaved, so a drift of the machine's speed hits every row alike
            loads.append(os.getloadavg()[0])
            walls[run].append(sweep_wall(run[0], samples, record, [*law, *stepping(run[1], run[2])]))
    numba_row = next((run for run in runs if run[0] == "numba"), None)
    print(
        f"\nwalls on 2 threads, {args.repeats} repeats interleaved (load average 1 min "
        f"{min(loads):.1f}–{max(loads):.1f}; this run uses 2):"
    )
    print(f"{'implementation':<10} {'scheme':<16} {'dt (s)':>8} {'median wall':>12} {'walls':>26} {'vs Numba':>9}")
    for run, times in walls.items():
        ratio = np.median(times) / np.median(walls[numba_row]) if numba_row else math.nan
        print(
            f"{run[0]:<10} {run[1]:<16} {run[2]:>8.3g} {np.median(times):>10.2f} s "
            f"{' '.join(f'{t:.2f}' for t in times):>26} {ratio:>8.2f}×"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="smaller run: 40 variants, short timings")
    parser.add_argument("--samples", type=int, default=200, help="sweep variants (default 200)")
    parser.add_argument("--record", type=float, default=1.0, help="sweep record after the release, s")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 16, 200, 1024])
    parser.add_argument("--libm-exp", action="store_true", help="glibc's scalar exp (Warp's) instead of libmvec's")
    parser.add_argument(
        "--law",
        choices=("tagawa2003", "masing"),
        default="tagawa2003",
        help="material.bending_law of every variant (default: the sweep's, tagawa2003)",
    )
    parser.add_argument(
        "--parts",
        nargs="+",
        choices=("agreement", "tables", "equal-accuracy"),
        default=["agreement", "tables"],
        help="what to run (default: agreement tables)",
    )
    parser.add_argument("--reference-dt", type=float, default=1e-6, help="equal accuracy: the explicit reference's dt")
    parser.add_argument("--tolerance", type=float, default=2e-3, help="equal accuracy: of the excursion (0.2 %%)")
    # Steps that divide the 1/600 s probe interval (and the 1.3 s hold), so that no sample
    # is off its time by up to dt/2, which at 4e-4 s alone is ~0.1 % of the excursion.
    parser.add_argument(
        "--explicit-ladder",
        type=float,
        nargs="+",
        default=[1 / (600 * n) for n in (40, 34, 33)],
        help="equal accuracy: semi_implicit steps, s (default 1/(600 n), n = 40, 34, 33)",
    )
    parser.add_argument(
        "--imex-ladder",
        type=float,
        nargs="+",
        default=[1 / (600 * n) for n in (16, 12, 10, 8, 6, 5, 4, 3, 2)],
        help="equal accuracy: imex and imex_trapezoidal steps, s (default 1/(600 n), n = 16, 12, 10, 8, 6, 5, 4, 3, 2)",
    )
    parser.add_argument("--repeats", type=int, default=3, help="equal accuracy: timed repeats of each wall")
    parser.add_argument(
        "--check-dt",
        type=float,
        default=0.0,
        help="equal accuracy: recheck the worst variants against this finer explicit dt (0: no)",
    )
    parser.add_argument("--check-worst", type=int, default=32, help="equal accuracy: how many variants to recheck")
    parser.add_argument(
        "--sweep-wall",
        nargs=3,
        metavar=("IMPL", "SCHEME", "DT"),
        help="only time one sweep (IMPL warpcloth or numba), nothing warmed up: for timing "
        "the whole process from outside",
    )
    args = parser.parse_args()
    global VECTOR_EXP
    VECTOR_EXP = 0 if args.libm_exp else VECTOR_EXP  # read when Numba compiles, i.e. at the first call
    if args.libm_exp:
        for function in (fresh_hinges, masing_follow, advance_block, advance):
            function._cache = NullCache()  # a cached compile would have baked libmvec's exp in
    samples = 40 if args.quick else args.samples
    law = [] if args.law == "tagawa2003" else [f'material.bending_law="{args.law}"']
    wp.config.log_level = logging.WARNING
    wp.init()
    if args.sweep_wall:
        impl, scheme, dt = args.sweep_wall
        wall = sweep_wall(impl, samples, args.record, [*law, *stepping(scheme, float(dt))])
        print(f"{impl} {scheme} dt = {float(dt):g} s, {samples} variants: sweep wall {wall:.3f} s")
        return
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    cores = os.cpu_count() or 1

    # ---- warm-up: compile every path (Numba's and Warp's) before anything is timed ----
    _s, warm = sweep_scenes(4, 0.01, law)
    for threads in (1, min(2, cores)):
        numba.set_num_threads(threads)
        peer = NumbaStrips(warm)
        peer.run()
    x0 = displaced_start(warm[0])
    warpcloth_wall(free_runs(4, 0.002, 2, law), x0, 1)
    print(
        f"machine: {machine()}; warp {wp.__version__} (cpu), numba {numba.__version__} "
        f"(threading layer {numba.threading_layer()}), numpy {np.__version__}; exp: "
        f"{f'libmvec {VECTOR_EXP}-wide' if VECTOR_EXP else 'glibc scalar'}; compile excluded (everything warmed "
        "up first)"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for scheme in ("semi_implicit", "imex", "imex_trapezoidal"):
            wc.run_sweep(
                sweep_scenes(4, 0.01, [*law, *stepping(scheme, 1e-5)])[0], Path(tmp) / scheme, workers=min(2, cores)
            )

    # ---- 1. the sweep: agreement and wall time, warpcloth on 2 threads vs Numba on 2 ----
    sweep, scenes = sweep_scenes(samples, args.record, law)
    if "agreement" in args.parts:
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            wc.run_sweep(sweep, Path(tmp) / "sweep", workers=min(2, cores), probes="all")  # tip_y compared too
            warp_sweep = time.perf_counter() - start
            numba.set_num_threads(min(2, cores))
            start = time.perf_counter()
            peer = NumbaStrips(scenes)
            peer.run()
            numba_sweep = time.perf_counter() - start
            gap, excursion = agreement(Path(tmp) / "sweep", peer)
            summary = pd.read_parquet(Path(tmp) / "sweep" / "summary.parquet")
        steps = int(peer.out_steps[-1])
        print(
            f"\nagreement: {samples} variants of damped_swing_sweep (D, D1, α, γ varied; law {args.law}), "
            f"hold and release replicated, {args.record:g} s record, tip x and y at {peer.kept} samples each: "
            f"largest gap {gap:.2e} m (tip excursion {excursion * 1e3:.0f} mm); Numba strips failing the "
            f"strain/fold check: {(peer.failed >= 0).sum()}"
        )
        if peer.masing:
            ours = summary["reversal_overflows"].to_numpy() if "reversal_overflows" in summary else "none recorded"
            print(
                f"reversal memory ({peer.capacity} points): Numba deepest {peer.deepest[:samples].max()}, "
                f"overflows {peer.overflows[:samples].sum()}; warpcloth's sweep overflows "
                f"{np.sum(ours) if not isinstance(ours, str) else ours}"
            )
        print(
            f"sweep wall ({samples} variants, {steps} steps each = {steps * scenes[0].integrator.dt_s:.2f} s "
            f"simulated incl. the hold): warpcloth run_sweep 2 threads {warp_sweep:.2f} s, "
            f"Numba 2 threads {numba_sweep:.2f} s: Numba {warp_sweep / numba_sweep:.2f}× faster"
        )

    # The cores may be shared: a busy core shows as 2-thread rows no faster than 1-thread ones.
    print(f"load average before the tables: {os.getloadavg()[0]:.2f} (this run uses up to 2)")

    # ---- 2. throughput tables ----
    if "tables" in args.parts:
        throughput_tables(args, law, samples, scenes[0].integrator.dt_s, x0, cores)

    # ---- 3. the sweep at equal accuracy ----
    if "equal-accuracy" in args.parts:
        equal_accuracy(args, law, samples)


def throughput_tables(
    args: argparse.Namespace, law: list[str], samples: int, dt: float, x0: np.ndarray, cores: int
) -> None:
    """Strip-steps/s and wall per simulated second of every implementation at each size."""
    budget = 0.25 if args.quick else 1.0  # target wall seconds per table cell
    print(f"\n{'B':>5} {'implementation':<22} {'strip-steps/s':>14} {'wall per sim s':>15} {'vs warpcloth 1T':>16}")
    rows = []
    for b in args.sizes:
        base = None
        results = []
        # Steps per cell sized from a rough rate so each cell takes about `budget` s.
        guess = {
            "warpcloth 1 thread": 1e6,
            "warpcloth 2 threads": 2e6,
            "numpy": min(3e5, 1e4 * b),
            "numba 1 thread": 3e6,
            "numba 2 threads": 6e6,
        }
        for name, rate in guess.items():
            threads = 2 if "2" in name else 1
            if threads > min(b, cores) or (name == "numpy" and law):  # NumPy has the paper's law only
                results.append((name, math.nan))
                continue
            n_steps = max(200, int(budget * rate / b))
            if name.startswith("warpcloth"):
                results.append((name, warpcloth_rate(samples, b, n_steps, dt, x0, threads, law)))
                continue
            if name == "numpy":
                strips = NumpyStrips(free_runs(samples, n_steps * dt, 1, law)[0], b, x0)
                start = time.perf_counter()
                for _ in range(n_steps):
                    strips.step()
                wall = time.perf_counter() - start
            else:
                numba.set_num_threads(threads)
                strips = NumbaStrips(free_runs(samples, n_steps * dt, b, law), np.repeat(x0[:, None, :], b, axis=1))
                start = time.perf_counter()
                strips.run(n_steps)
                wall = time.perf_counter() - start
            results.append((name, b * n_steps / wall))
        base = results[0][1]
        for name, rate in results:
            if math.isnan(rate):
                print(f"{b:>5} {name:<22} {'—':>14} {'—':>15} {'—':>16}")
            elif math.isnan(base):
                print(f"{b:>5} {name:<22} {rate:>14.3e} {b / (rate * dt):>13.3g} s {'—':>16}")
            else:
                print(f"{b:>5} {name:<22} {rate:>14.3e} {b / (rate * dt):>13.3g} s {rate / base:>15.2f}×")
            rows.append((b, name, rate))


if __name__ == "__main__":
    main()
