"""The bending law on its own: moment along prescribed curvature paths.

Runs the strip kernel's hinge logic (the same Warp functions) on curvature histories, for
plotting a material's KES loop, fitting it, and testing the law in isolation.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import warp as wp

from warpcloth.kernels import laws, precision

from .material import MaterialSI
from .model import machine_device
from .state import allocate_reversal_memory


def moment_along_path(materials: MaterialSI | Sequence[MaterialSI], curvature: np.ndarray,
                      device: str | None = "cpu", with_tangent: bool = False,
                      reversal_memory: int | None = None) -> tuple[np.ndarray, ...]:
    """Moment per width M (N·m/m) along curvature paths (1/m), one column per material.

    ``curvature`` is ``[sample]`` (one path for every material) or ``[sample, path]``; M is
    ``[sample, material]``, or ``[sample]`` for one material on one path. Each hinge starts fresh at its
    first sample (no hysteretic moment, loading up), and follows each material's own
    bending law. Returns ``(M, work)`` where
    ``work[path]`` = Σ M_n (K_{n+1} − K_n), the bending work per width (N), accumulated
    with a left-point rule; with ``with_tangent`` also the law's dM/dK (N·m), shaped as M.
    ``reversal_memory`` caps the reversal points a masing hinge keeps (default: as many as
    the path has reversals, so none is ever dropped).
    """
    materials = [materials] if isinstance(materials, MaterialSI) else list(materials)
    k = np.asarray(curvature, dtype=np.float64)
    single = k.ndim == 1 and len(materials) == 1  # one path, one material: M as [sample]
    if k.ndim == 1:
        k = k[:, None]
    if k.shape[1] == 1 and len(materials) > 1:
        k = np.repeat(k, len(materials), axis=1)
    if k.shape[1] != len(materials):
        raise ValueError(f"{k.shape[1]} curvature paths for {len(materials)} materials")
    device = machine_device(device)  # Warp started quietly, as for a run
    law = laws.build(wp.float64)
    parameters = wp.array(np.array([m.bending_parameters() for m in materials]), dtype=law.Parameters,
                          device=device)
    if reversal_memory is None:  # every sign change of dK can open a point
        reversal_memory = int(np.abs(np.diff(np.sign(np.diff(k, axis=0)), axis=0)).sum(axis=0).max(initial=0)) // 2 + 1
    if not (isinstance(reversal_memory, int) and reversal_memory >= 1):
        raise ValueError(f"reversal_memory must be a whole number of at least 1, got {reversal_memory!r}")
    history = allocate_reversal_memory(law.History, reversal_memory, 1, k.shape[1], precision(wp.float64).vec2, device)
    moment = wp.zeros(k.shape, dtype=wp.float64, device=device)
    slope = wp.zeros(k.shape, dtype=wp.float64, device=device)
    work = wp.zeros(k.shape[1], dtype=wp.float64, device=device)
    wp.launch(law.moment_along_path, dim=k.shape[1], device=device,
              inputs=[wp.array(np.ascontiguousarray(k), dtype=wp.float64, device=device), parameters, history, moment,
                      slope, work])
    m, dm = moment.numpy(), slope.numpy()
    if single:
        m, dm = m[:, 0], dm[:, 0]
    return (m, work.numpy(), dm) if with_tangent else (m, work.numpy())
