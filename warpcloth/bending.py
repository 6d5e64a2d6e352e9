"""The hysteretic bending law on its own: moment along a prescribed curvature path.

Runs the strip kernel's hinge logic (same Warp functions) on curvature histories, for
plotting a material's KES loop, fitting it, and testing the law in isolation.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import warp as wp

from warpcloth.kernels import build_kernels

from .material import MaterialSI


def moment_along_path(materials: MaterialSI | Sequence[MaterialSI], curvature: np.ndarray,
                      device: str | None = "cpu") -> tuple[np.ndarray, np.ndarray]:
    """Moment per width M (N·m/m) along curvature paths (1/m), one column per material.

    ``curvature`` is ``[sample]`` or ``[sample, path]``; each hinge starts fresh at its
    first sample (rising branch, no hysteretic offset). Returns ``(M, work)`` where
    ``work[path]`` = Σ M_n (K_{n+1} − K_n), the bending work per width (J/m² · m = N),
    accumulated with the strip kernel's left-point rule.
    """
    materials = [materials] if isinstance(materials, MaterialSI) else list(materials)
    k = np.asarray(curvature, dtype=np.float64)
    single = k.ndim == 1
    if single:
        k = k[:, None]
    if k.shape[1] == 1 and len(materials) > 1:
        k = np.repeat(k, len(materials), axis=1)
    if k.shape[1] != len(materials):
        raise ValueError(f"{k.shape[1]} curvature paths for {len(materials)} materials")
    kern = build_kernels(wp.float64)

    def per_path(name: str) -> wp.array:
        return wp.array(np.array([getattr(m, name) for m in materials]), dtype=wp.float64, device=device)

    moment = wp.zeros(k.shape, dtype=wp.float64, device=device)
    work = wp.zeros(k.shape[1], dtype=wp.float64, device=device)
    wp.launch(kern.moment_along_path, dim=k.shape[1], device=device,
              inputs=[wp.array(np.ascontiguousarray(k), dtype=wp.float64, device=device),
                      per_path("bending_rigidity"), per_path("hysteresis_d1"), per_path("hysteresis_alpha"),
                      per_path("hysteresis_k0"), per_path("hysteresis_m0"), moment, work])
    m = moment.numpy()
    return (m[:, 0] if single else m), work.numpy()
