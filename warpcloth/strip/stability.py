"""The step that explicit bending allows, from the linearised hanging chain.

Symplectic Euler is stable while ω·dt < 2 for every mode it integrates explicitly. The
stretching mode has an exact bound (:meth:`SemiImplicitEulerSolver.step_limit`); once it
is implicit (imex), the stiffest explicit motion is transverse: the bending couples at the
law's stiffest tangent plus the tension's geometric stiffness T/h. This module computes
that mode's frequency for the straight hanging chain (docs/model.md §9.6): an estimate,
not a bound like the stretching limit, because a hysteretic law's tangent reaches its
maximum only just after a reversal and a deflected strip is not straight. Measured against
runs: 4.46e-4 s predicted for the elastic impulsive rotation at h = 2.5 mm (it runs at
4.4e-4 s), 2.59e-4 s for the masing one (it runs to 2.89e-4 s).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .bending import moment_along_path
from .builder import Grip, hinge_intervals
from .material import MaterialSI

CYCLE_CURVATURE = 1000.0
"""1/m: the curvature amplitude of the cycles along which a law's stiffest tangent is
sought (10 1/cm, four times the KES-FB2 range): a hysteretic tangent peaks just after a
reversal from near saturation, which this reaches for every bundled material."""
CYCLE_SAMPLES = 200
"""Samples per leg between the reversals; each leg's first step after its reversal is
1e-9 of the amplitude, so the tangent is read where it peaks."""


def _cycle_path() -> tuple[np.ndarray, int, int]:
    # 0 → +K, then two full cycles +K → −K → +K; returns the path and the samples of the
    # last cycle's K = 0 going down and going up (each leg has one at exactly 0)
    k, n = CYCLE_CURVATURE, CYCLE_SAMPLES
    down = np.concatenate([[k * (1 - 1e-9)], np.linspace(k, -k, n + 1)[1:]])
    legs = [np.linspace(0.0, k, n + 1), down, -down, down, -down]
    starts = np.cumsum([0] + [len(leg) for leg in legs])
    return np.concatenate(legs), int(starts[3] + 1 + n // 2 - 1), int(starts[4] + 1 + n // 2 - 1)


_CYCLES: dict[MaterialSI, tuple[float, float]] = {}


def cycle_response(materials: Sequence[MaterialSI]) -> list[tuple[float, float]]:
    """Per material, the largest dM/dK (N·m) its bending law reaches and its loop width at
    K = 0 (N·m/m; 0 for an elastic law), along two full cycles between
    ±:data:`CYCLE_CURVATURE` after a virgin loading (the law's own kernel, one launch for
    every material not seen before)."""
    todo = list(dict.fromkeys(m for m in materials if m not in _CYCLES))
    if todo:
        path, down, up = _cycle_path()
        moment, _, tangent = moment_along_path(todo, path, with_tangent=True, reversal_memory=8)
        moment, tangent = moment.reshape(len(path), -1), tangent.reshape(len(path), -1)
        for i, material in enumerate(todo):
            _CYCLES[material] = (float(tangent[:, i].max()), float(abs(moment[down, i] - moment[up, i])))
    return [_CYCLES[m] for m in materials]


def stiffest_tangent(material: MaterialSI) -> float:
    """The largest dM/dK (N·m) the material's bending law reaches (:func:`cycle_response`)."""
    return cycle_response([material])[0][0]


def is_hysteretic(material: MaterialSI) -> bool:
    """Whether the material's bending law has a loop: at K = 0 the moment going down
    differs from the moment going up (:func:`cycle_response`)."""
    return cycle_response([material])[0][1] > 0.0


def transverse_step_limit(
    material: MaterialSI,
    spacing: float,
    free_nodes: int,
    edge_hinge_length: float,
    gravity: float,
    grip: Grip | None = None,
) -> float:
    """2/ω_max (s) of the straight hanging chain's transverse modes: ``free_nodes`` nodes
    below the clamp edge at ``spacing`` (m), masses ρ_A·h (the free end half), hinge
    stiffness tangent·(h/edge_hinge_length)/h at the clamp-edge hinge and tangent/h below
    it on the turning angles, and the geometric stiffness T_j/h of each segment under the
    weight below it (``gravity`` in m/s²). A ``grip`` scales each hinge's elastic part D
    and its hysteretic part (tangent − D) by the hinge's factors (§5.4). Per unit width:
    the width cancels."""
    h, n = spacing, free_nodes
    mass = np.full(n, material.density * h)
    mass[-1] *= 0.5
    tangent, rigidity = stiffest_tangent(material), material.bending_rigidity
    factors = (grip or Grip()).hinge_factors(hinge_intervals(h, n))
    couple = (factors[:, 0] * rigidity + factors[:, 1] * (tangent - rigidity)) / h
    couple[0] *= h / edge_hinge_length
    # hinge j turns at node j (node 0: the clamp edge, held; node -1 inside the clamp) by
    # (y[j+1] - 2 y[j] + y[j-1]) / h; segment j (node j to j + 1) stretches by y[j+1] - y[j]
    # and carries the weight of nodes j + 1..n. Unknowns: nodes 1..n (column k is node k + 1).
    turning = (np.eye(n, k=-2) - 2 * np.eye(n, k=-1) + np.eye(n)) / h
    stretch = np.eye(n) - np.eye(n, k=-1)
    spring = gravity * np.cumsum(mass[::-1])[::-1] / h
    stiffness = turning.T @ (couple[:, None] * turning) + stretch.T @ (spring[:, None] * stretch)
    scale = 1.0 / np.sqrt(mass)
    omega_squared = float(np.linalg.eigvalsh(scale[:, None] * stiffness * scale[None, :]).max())
    return float(2.0 / np.sqrt(omega_squared))
