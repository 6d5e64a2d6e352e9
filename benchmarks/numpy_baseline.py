"""warpcloth against a plain NumPy implementation of the same model, vectorised over the batch.

    python benchmarks/numpy_baseline.py [--sizes 1 64 1024] [--steps 2000]

The NumPy code below is what a user would otherwise write: the same tensile law,
circumcircle curvature, the paper's hysteresis as docs/model.md §4.3 writes it (a loop
centre moved by the inverse branch at each reversal; the kernel carries the gap to the
asymptote instead, the same law to rounding), bending forces, gravity, damping and
semi-implicit Euler, one array operation per term over all strips (fixed clamp). It is
first checked to follow the same trajectory as warpcloth on the paper's law's swing
(``damped_swing_paper``), then both are timed on the same batch in the same run; the
table prints strip-steps/s and the ratio.
The baseline skips the energy bookkeeping warpcloth does, which favours NumPy.
"""

from __future__ import annotations

import argparse
import logging
import platform
import time

import numpy as np
import warp as wp
from warpcloth.kernels.bending_tagawa2003 import loop_asymptote

import warpcloth as wc
from warpcloth.scene import rest_positions, to_si


class NumpyStrips:
    """B strips of one scene, advanced by NumPy array operations (arrays [strip, node])."""

    def __init__(self, scene: wc.Scene, batch: int, x0: np.ndarray) -> None:
        if scene.material.bending_law != "tagawa2003":
            raise ValueError(f"the NumPy baseline has the paper's law only, not {scene.material.bending_law!r}")
        m = to_si(scene.material)
        self.a = np.array(m.tensile)
        b = m.bending
        self.d, self.d1, self.alpha, self.k0 = m.bending_rigidity, b.hysteresis_d1, b.hysteresis_alpha, b.hysteresis_k0
        self.m0 = loop_asymptote(self.d1, self.alpha, self.k0)
        self.width = scene.strip.width_mm * 1e-3
        self.h = scene.spacing
        self.nc = scene.n_clamped
        self.dt = scene.integrator.dt_s
        self.gamma = scene.damping.gamma_per_s
        self.g = scene.run.gravity_m_per_s2
        n = scene.n_nodes
        self.mass = np.full(n, m.density * self.width * self.h)
        self.mass[-1] *= 0.5
        self.x = np.repeat(x0[None], batch, axis=0)
        self.v = np.zeros_like(self.x)
        # the clamp-edge hinge bends the half segment below the built-in end by default
        # (clamp.edge_hinge = "second_order", docs/model.md §5.3): twice the chain's curvature
        self.edge_scale = np.ones(n - self.nc)
        self.edge_scale[0] = 2.0 if scene.clamp.edge_hinge == "second_order" else 1.0
        k = self.curvature()
        self.branch = np.ones_like(k)
        self.centre = self.centre_through(k, np.zeros_like(k), self.branch)
        self.k_prev = k
        self.starting = True

    def curvature(self) -> np.ndarray:
        e = np.diff(self.x[:, self.nc - 2 :], axis=1)
        e1, e2 = e[:, :-1], e[:, 1:]
        cross = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
        return (
            self.edge_scale
            * 2
            * cross
            / (np.linalg.norm(e1, axis=-1) * np.linalg.norm(e2, axis=-1) * np.linalg.norm(e1 + e2, axis=-1))
        )

    def offset(self, u: np.ndarray, branch: np.ndarray) -> np.ndarray:
        rising = self.m0 - self.d1 * np.exp(-self.alpha * (self.k0 + u))
        falling = -self.m0 + self.d1 * np.exp(-self.alpha * (self.k0 - u))
        return np.where(branch > 0, rising, falling)

    def centre_through(self, k: np.ndarray, offset: np.ndarray, branch: np.ndarray) -> np.ndarray:
        if self.d1 <= 0:
            return k
        limit = self.m0 * (1 - 1e-12)
        h = np.clip(offset, -limit, limit)
        with np.errstate(invalid="ignore", divide="ignore"):
            rising = k + self.k0 + np.log((self.m0 - h) / self.d1) / self.alpha
            falling = k - self.k0 - np.log((h + self.m0) / self.d1) / self.alpha
        return np.where(branch > 0, rising, falling)

    def step(self) -> None:
        nc = self.nc
        f = np.zeros_like(self.x)
        e = np.diff(self.x[:, nc - 2 :], axis=1)  # clamp-edge segment first
        length = np.linalg.norm(e, axis=-1)
        strain = (length[:, 1:] - self.h) / self.h
        s = np.abs(strain)
        tension = np.sign(strain) * s * (self.a[0] + s * (self.a[1] + s * (self.a[2] + s * self.a[3])))
        seg = (tension * self.width / length[:, 1:])[..., None] * e[:, 1:]
        f[:, nc - 1 : -1] += seg
        f[:, nc:] -= seg
        e1, e2 = e[:, :-1], e[:, 1:]
        l1, l2 = length[:, :-1], length[:, 1:]
        cross = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
        k = self.edge_scale * 2 * cross / (l1 * l2 * np.linalg.norm(e1 + e2, axis=-1))
        reverse = (k - self.k_prev) * self.branch < 0
        if reverse.any():
            held = self.offset(self.k_prev - self.centre, self.branch)
            flipped = -self.branch
            self.centre = np.where(reverse, self.centre_through(self.k_prev, held, flipped), self.centre)
            self.branch = np.where(reverse, flipped, self.branch)
        self.k_prev = k
        tau = (self.d * k + self.offset(k - self.centre, self.branch)) * self.width
        grad_i = np.stack([-e1[..., 1], e1[..., 0]], axis=-1) / (l1**2)[..., None]
        grad_k = np.stack([-e2[..., 1], e2[..., 0]], axis=-1) / (l2**2)[..., None]
        f[:, nc - 2 : -2] -= tau[..., None] * grad_i
        f[:, nc:] -= tau[..., None] * grad_k
        f[:, nc - 1 : -1] += tau[..., None] * (grad_i + grad_k)
        m = self.mass[nc:, None]
        free = slice(nc, None)
        f[:, free] += -self.gamma * m * self.v[:, free] + m * np.array([0.0, -self.g])
        # velocities at half steps; the first kick from velocities known at the step itself
        # is half of one (kernels/integrators.py kick_mass, docs/model.md §9.1)
        self.v[:, free] += f[:, free] * (self.dt / (2 * m if self.starting else m))
        self.starting = False
        self.x[:, free] += self.v[:, free] * self.dt


def displaced_start(scene: wc.Scene) -> np.ndarray:
    """The straight strip with its free part turned 20° about the clamp edge."""
    x = rest_positions(scene)
    edge = x[scene.n_clamped - 1].copy()
    c, s = np.cos(0.35), np.sin(0.35)
    x[scene.n_clamped :] = edge + (x[scene.n_clamped :] - edge) @ np.array([[c, s], [-s, c]])
    return x


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 64, 1024])
    parser.add_argument("--steps", type=int, default=2000)
    args = parser.parse_args()
    wp.config.log_level = logging.WARNING
    wp.init()
    print(f"machine: {platform.machine()}, {platform.system()}, warp {wp.__version__} on cpu, numpy {np.__version__}")
    free = ["release.enabled=false", "damping.gamma_per_s=0.3"]
    scene = wc.load_scene("damped_swing_paper", free)
    x0 = displaced_start(scene)
    dt = scene.integrator.dt_s

    # Same trajectory: 0.05 s from the displaced start, tip position compared.
    check = wc.load_scene("damped_swing_paper", [*free, "run.duration_s=0.05"])
    reference = wc.simulate(check, initial_positions=x0[:, None, :])
    baseline = NumpyStrips(check, 1, x0)
    for _ in range(round(0.05 / dt)):
        baseline.step()
    gap = np.abs(baseline.x[0, -1] - [reference.probe("tip_x", 0)[-1], reference.probe("tip_y", 0)[-1]]).max()
    print(f"same trajectory: tip after 0.05 s differs by {gap:.2e} m (rounding only)")
    assert gap < 1e-12

    print(f"\n{'batch':>6} {'numpy strip-steps/s':>20} {'warpcloth strip-steps/s':>24} {'ratio':>7}")
    for batch in args.sizes:
        strips = NumpyStrips(scene, batch, x0)
        start = time.perf_counter()
        for _ in range(args.steps):
            strips.step()
        numpy_rate = batch * args.steps / (time.perf_counter() - start)
        timed = wc.load_scene("damped_swing_paper", [*free, f"run.duration_s={args.steps * dt}"])
        start = time.perf_counter()
        wc.simulate([timed] * batch, initial_positions=np.repeat(x0[:, None, :], batch, axis=1), keep_frames=False)
        warp_rate = batch * args.steps / (time.perf_counter() - start)
        print(f"{batch:>6} {numpy_rate:>20.3e} {warp_rate:>24.3e} {warp_rate / numpy_rate:>6.1f}x")


if __name__ == "__main__":
    main()
