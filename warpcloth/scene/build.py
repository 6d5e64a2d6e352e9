"""Scenes → simulation objects: the only place that reads scene fields to simulate.

A batch is one scene per strip; fields that are not ``per_strip`` must agree across it.
Offsets in the scene (rotation centre, hold target, laser line) are measured from the
clamp's lowest point in mm; here they become absolute positions in m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from warpcloth import units
from warpcloth.core.resources import check_memory
from warpcloth.errors import SceneError
from warpcloth.kernels import bending_law
from warpcloth.strip import SOLVERS, ClampMotion, FabricSet, Recorder, Solver, StripBuilder, StripControl, StripModel
from warpcloth.strip.stability import cycle_response

from .clamp_motion import clamp_pieces
from .geometry import rest_positions
from .grip import grip_of
from .materials import to_si
from .schema import Scene, batch_fields
from .step import AUTO, check_step


@dataclass
class Batch:
    """What :func:`build_batch` makes: the model, its drives, the solver and the recorder."""

    model: StripModel
    control: StripControl
    solver: Solver
    recorder: Recorder


def check_batch(scenes: Sequence[Scene]) -> None:
    """Raise SceneError unless every batch-level field agrees across ``scenes`` and every
    scene's step can run (:func:`check_step`; load_scene and load_sweep check it earlier,
    where they can say which line to change)."""
    if not scenes:
        raise SceneError("scenes", "a batch needs at least one scene")
    chosen = [to_si(s.material) for s in scenes if s.integrator.dt_chosen_by == AUTO]
    if chosen:  # the laws' cycles for check_step's auto check: one launch, not one per scene
        cycle_response(chosen)
    for i, scene in enumerate(scenes):
        try:
            check_step(scene)
        except SceneError as exc:
            raise SceneError(
                exc.field, f"variant {i}: {exc.message}" if len(scenes) > 1 else exc.message, exc.related, i
            ) from None
    first = scenes[0].to_dict()
    for i, scene in enumerate(scenes[1:], start=1):
        other = scene.to_dict()
        for name in batch_fields():
            section, key = name.split(".")
            if first[section][key] != other[section][key]:
                raise SceneError(
                    name,
                    f"differs between variant 0 ({first[section][key]!r}) and variant {i} "
                    f"({other[section][key]!r}); it cannot vary within one batch",
                )


def builder_for(scenes: Sequence[Scene]) -> StripBuilder:
    """A :class:`StripBuilder` holding one strip per scene, in SI."""
    check_batch(scenes)
    first = scenes[0]
    # the model's per-node arrays (positions, velocities, three force parts, imex's two
    # scratch arrays, rest positions, hinge memory, rest curvature and grip factors: ~29
    # numbers of 8 B per node and strip), before any exists
    remembers = any(bending_law(scene.material.bending_law).uses_reversal_memory for scene in scenes)
    history = 16 * (first.integrator.reversal_memory + 1) * first.n_nodes if remembers else 0
    check_memory(
        (232 * first.n_nodes + history) * len(scenes),
        f"the state of {len(scenes)} strip(s) of {first.n_nodes} nodes",
        "use a coarser strip.spacing_mm, fewer strips per batch"
        + (" or a smaller integrator.reversal_memory" if remembers else ""),
    )
    builder = StripBuilder(
        rest_positions(first),
        first.n_clamped,
        first.spacing,
        first.run.gravity_m_per_s2,
        release_time=first.preroll,
        move_time=first.release.move_time_s,
        reversal_memory=first.integrator.reversal_memory,
    )
    for scene in scenes:
        start, end, coefficients = clamp_pieces(scene.clamp)
        builder.add_strip(
            to_si(scene.material),
            width=scene.strip.width_mm * units.LENGTH_MM,
            damping=scene.damping.gamma_per_s,
            clamp=ClampMotion(start, end, coefficients),
            rotation_centre=units.LENGTH_MM
            * np.array([scene.clamp.rotation_centre_dx_mm, scene.clamp.rotation_centre_dy_mm]),
            hold_target=units.LENGTH_MM * np.array([scene.release.hold_x_mm, scene.release.hold_y_mm]),
            settle_damping=scene.release.settle_damping_per_s,
            hold_free_end=scene.release.hold_free_end,
            edge_hinge_length=scene.edge_hinge_length,
            fabric_set=FabricSet(
                scene.strip.rest_curvature_per_cm * units.CURVATURE_PER_CM,
                tuple(s * units.LENGTH_MM for s in scene.strip.rest_curvature_table_s_mm),
                tuple(k * units.CURVATURE_PER_CM for k in scene.strip.rest_curvature_table_per_cm),
            ),
            grip=grip_of(scene),
        )
    return builder


def build_batch(scenes: Sequence[Scene], device: str | None = None, terms: tuple = ()) -> Batch:
    """Model, control, solver and recorder of one batch of scenes, with the force ``terms``
    (:mod:`warpcloth.kernels.force_terms`) acting on every free node."""
    first = scenes[0] if scenes else None
    builder = builder_for(scenes)
    integrator = first.integrator
    model = builder.finalize(device=device, precision=integrator.precision, terms=terms)
    solver = SOLVERS[integrator.scheme](model, dt=integrator.dt_s, divergence_strain=integrator.divergence_strain)
    recorder = Recorder(
        interval=first.output_interval,
        probes_per_frame=first.output.probes_per_frame,
        duration=first.run.duration_s,
        laser_height=first.output.laser_height_mm * units.LENGTH_MM,
        loop_hinge=first.loop_hinge,
    )
    return Batch(model, model.control(), solver, recorder)
