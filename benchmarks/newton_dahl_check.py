"""warpcloth's Dahl law against NVIDIA Newton's cable Dahl state on the same curvature path
(run by hand; issue 15). Two steps, because Newton pins its own Warp:

    python -m venv /tmp/nvenv && /tmp/nvenv/bin/pip install newton
    /tmp/nvenv/bin/python benchmarks/newton_dahl_check.py newton /tmp/newton_dahl.npz
    python benchmarks/newton_dahl_check.py warpcloth /tmp/newton_dahl.npz

The first runs Newton's ``_advance_dahl_axis`` (newton/_src/solvers/vbd/rigid_vbd_kernels.py:
σ ← d σ_max (1 − e^{−d Δκ/τ}) + σ e^{−d Δκ/τ}; in Newton 1.8.0
``_advance_dahl_axis(dκ, dκ_prev, σ, σ_max, τ)``) along a random curvature path with many
reversals of every size; the second runs warpcloth's ``dahl`` law (n = 1, M_s = σ_max,
K_s = τ, D = 0) along the same path and prints the largest difference.
"""

import sys

import numpy as np

SIGMA_MAX, TAU = 2e-4, 30.0  # N (0.02 gf·cm/cm) and 1/m (0.3 1/cm)


def path() -> np.ndarray:
    rng = np.random.default_rng(7)
    steps = rng.normal(0, 0.6, 4000) * (1 + 4 * (rng.random(4000) < 0.05))
    return np.cumsum(steps)


def newton_states(curvature: np.ndarray) -> np.ndarray:
    import warp as wp
    from newton._src.solvers.vbd.rigid_vbd_kernels import _advance_dahl_axis

    @wp.kernel
    def follow(kappa: wp.array(dtype=float), sigma: wp.array(dtype=float), sigma_max: float, tau: float):
        s = wp.float32(0.0)  # mutable in the loop (a literal would be a constant)
        d_prev = wp.float32(0.0)
        for n in range(1, kappa.shape[0]):
            d_kappa = kappa[n] - kappa[n - 1]
            s, direction = _advance_dahl_axis(d_kappa, d_prev, s, sigma_max, tau)
            d_prev = d_kappa
            sigma[n] = s

    kappa = wp.array(curvature.astype(np.float32), dtype=float)
    sigma = wp.zeros(len(curvature), dtype=float)
    wp.launch(follow, dim=1, inputs=[kappa, sigma, SIGMA_MAX, TAU])
    return sigma.numpy().astype(np.float64)


def warpcloth_states(curvature: np.ndarray) -> np.ndarray:
    import warpcloth as wc
    from warpcloth.scene import to_si
    from warpcloth.strip import moment_along_path

    material = to_si(
        wc.load_scene(
            "damped_swing",
            {
                "material.bending_law": "dahl",
                "material.bending_rigidity_gf_cm2_per_cm": 0.0,
                "material.dahl_moment_gf_cm_per_cm": SIGMA_MAX / 9.80665e-3,
                "material.dahl_curvature_per_cm": TAU / 100,
                "material.dahl_exponent": 1.0,
            },
        ).material
    )
    moment, _ = moment_along_path(material, curvature)
    return moment


if __name__ == "__main__":
    which, file = sys.argv[1], sys.argv[2]
    if which == "newton":
        k = path()
        np.savez(file, curvature=k, sigma=newton_states(k))
    else:
        saved = np.load(file)
        # Newton's float32 path, read back exactly, is what both follow
        k = saved["curvature"].astype(np.float32).astype(np.float64)
        ours = warpcloth_states(k)
        gap = np.abs(ours - saved["sigma"]).max()
        print(
            f"{len(k)} samples, {int(np.sum(np.diff(np.sign(np.diff(k))) != 0))} reversals: largest |Δσ| = "
            f"{gap:.3g} N = {gap / SIGMA_MAX:.2e} of σ_max (Newton computes in float32)"
        )
