"""The laws on their own: bending moment along prescribed curvature paths, shear force
along prescribed shear-angle paths.

Runs the strip kernel's hinge logic (the same Warp functions) on such histories, for
plotting a material's KES loops, fitting them, and testing a law in isolation.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import warp as wp

from warpcloth.errors import ArgumentError
from warpcloth.kernels import laws, packed_parameters, precision
from warpcloth.kernels.law import BENDING_RIGIDITY

from .material import LawParameters, MaterialSI
from .model import machine_device
from .state import allocate_reversal_memory, check_reversal_memory


def moment_along_path(
    materials: MaterialSI | Sequence[MaterialSI],
    curvature: np.ndarray,
    device: str | None = "cpu",
    with_tangent: bool = False,
    reversal_memory: int | None = None,
) -> tuple[np.ndarray, ...]:
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
    return law_along_path([m.bending_parameters() for m in materials], curvature, device, with_tangent, reversal_memory)


def shear_force_along_path(
    shear: Sequence[tuple[float, LawParameters]],
    angle: np.ndarray,
    device: str | None = "cpu",
    with_tangent: bool = False,
) -> tuple[np.ndarray, ...]:
    """Shear force per width Fs = G φ + h(φ) (N/m) along shear-angle paths (rad), one column
    per ``(G, law)`` (G in N/(m·rad), :meth:`warpcloth.scene.ShearMaterial.si`): the same
    law functions as :func:`moment_along_path`, the angle for the curvature. Shapes and
    the returned work (N·rad/m) as there."""
    packed = [packed_parameters(law.law, {BENDING_RIGIDITY.name: rigidity, **law.as_dict()}) for rigidity, law in shear]
    return law_along_path(packed, angle, device, with_tangent)


def law_along_path(
    packed: Sequence[tuple[float, ...]],
    path: np.ndarray,
    device: str | None = "cpu",
    with_tangent: bool = False,
    reversal_memory: int | None = None,
) -> tuple[np.ndarray, ...]:
    """The laws' response D x + h(x) along paths ``x``, one column per packed parameter
    vector (kernels/laws.py): :func:`moment_along_path` and :func:`shear_force_along_path`
    in one kernel launch."""
    k = np.asarray(path, dtype=np.float64)
    single = k.ndim == 1 and len(packed) == 1  # one path, one law: the response as [sample]
    if k.ndim == 1:
        k = k[:, None]
    if k.shape[1] == 1 and len(packed) > 1:
        k = np.repeat(k, len(packed), axis=1)
    if k.shape[1] != len(packed):
        raise ArgumentError("path", f"{k.shape[1]} paths for {len(packed)} materials")
    device = machine_device(device)  # Warp started quietly, as for a run
    law = laws.build(wp.float64)
    parameters = wp.array(np.array(packed), dtype=law.Parameters, device=device)
    if reversal_memory is None:  # every sign change of dK can open a point
        reversal_memory = int(np.abs(np.diff(np.sign(np.diff(k, axis=0)), axis=0)).sum(axis=0).max(initial=0)) // 2 + 1
    check_reversal_memory(reversal_memory)
    history = allocate_reversal_memory(law.History, reversal_memory, 1, k.shape[1], precision(wp.float64).vec2, device)
    moment = wp.zeros(k.shape, dtype=wp.float64, device=device)
    slope = wp.zeros(k.shape, dtype=wp.float64, device=device)
    work = wp.zeros(k.shape[1], dtype=wp.float64, device=device)
    wp.launch(
        law.moment_along_path,
        dim=k.shape[1],
        device=device,
        inputs=[
            wp.array(np.ascontiguousarray(k), dtype=wp.float64, device=device),
            parameters,
            history,
            moment,
            slope,
            work,
        ],
    )
    m, dm = moment.numpy(), slope.numpy()
    if single:
        m, dm = m[:, 0], dm[:, 0]
    return (m, work.numpy(), dm) if with_tangent else (m, work.numpy())
