"""What is recorded of every strip at each output sample (docs/model.md §12).

The probe buffer is ``[sample, field, strip]`` with fields in :data:`STRIP_PROBES`
order; the kernel writes each field through its named slot, so adding a probe is one
description here and one line in ``record_probes`` (the budget and units follow from
the description).
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import drives, fused, integrators, structs, tensile
from .probe_set import STORED, WORK_AGAINST, WORK_BY, Probe, ProbeSet

STRIP_PROBES = ProbeSet(
    (
        Probe("tip_x", "m"),
        Probe("tip_y", "m"),
        Probe("tip_speed", "m/s"),
        Probe("laser_x", "m (NaN when the strip misses the line)"),
        Probe("clamp_angle", "rad"),
        Probe("kinetic", "J", STORED),
        Probe("gravitational", "J", STORED),
        Probe("tensile", "J", STORED),
        Probe("bending_elastic_work", "J", WORK_AGAINST),
        Probe("hysteresis_work", "J", WORK_AGAINST),
        Probe("damping_work", "J", WORK_AGAINST),
        Probe("drive_work", "J", WORK_BY),
        Probe("loop_curvature", "1/m (output.loop_hinge_mm)"),
        Probe("loop_moment", "N·m/m (moment per width)"),
    )
)
"""What a strip records, in the order of the probe buffer's second axis (SI), with each
quantity's place in the energy budget; a model's force terms append their channels."""

PROBE_FIELDS = STRIP_PROBES.fields
"""Probe quantities of a strip without force terms, in buffer order."""

PROBE_INDEX = STRIP_PROBES.index
"""Slot of each probe quantity."""

PROBE_UNITS = STRIP_PROBES.units
"""SI unit of each probe quantity, as written into a run directory's meta.json."""


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = ()) -> SimpleNamespace:
    """The ``ProbeSettings`` struct and ``record_probes`` for ``scalar`` and force ``terms``."""
    zero = scalar(0.0)
    half = scalar(0.5)
    strip = structs.build(scalar, terms)
    probe_set = STRIP_PROBES.with_terms(terms)
    record_work = fused.tally_recorder(scalar, strip.tally, probe_set.channel_slots, probe_set.channel_signs)
    StripModel, StripState, law = strip.StripModel, strip.StripState, strip.law
    drive = drives.build(scalar)
    StripControl, clamp_angle = drive.StripControl, drive.clamp_angle
    Stepping = integrators.build(scalar).Stepping
    tensile_energy = tensile.build(scalar).energy_per_width
    slot = SimpleNamespace(**PROBE_INDEX)
    TIP_X, TIP_Y, TIP_SPEED, LASER_X, CLAMP_ANGLE = (
        slot.tip_x,
        slot.tip_y,
        slot.tip_speed,
        slot.laser_x,
        slot.clamp_angle,
    )
    KINETIC, GRAVITATIONAL, TENSILE = slot.kinetic, slot.gravitational, slot.tensile
    LOOP_CURVATURE, LOOP_MOMENT = slot.loop_curvature, slot.loop_moment

    @wp.struct
    class ProbeSettings:
        """Where the recorder looks: the laser line, the probed hinge, the frame stride."""

        laser_height: scalar  # y of the horizontal laser line, m
        loop_hinge: int  # hinge whose curvature and moment are probed (0 = clamp edge)
        probes_per_frame: int  # probe samples per shape frame

    @wp.func
    def laser_crossing(model: StripModel, state: StripState, s: int, height: scalar):
        # x where the strip first crosses y = height, searching down from the clamp edge.
        for i in range(model.n_clamped - 1, model.n_nodes - 1):
            p = state.position[i, s]
            q = state.position[i + 1, s]
            if (p[1] - height) * (q[1] - height) <= zero and p[1] != q[1]:
                return p[0] + (q[0] - p[0]) * (height - p[1]) / (q[1] - p[1])
        return scalar(wp.nan)

    @wp.func
    def record_probes(
        model: StripModel,
        control: StripControl,
        stepping: Stepping,
        state: StripState,
        settings: ProbeSettings,
        s: int,
        step: int,
        probes: wp.array3d(dtype=scalar),
        k: int,
    ):
        # Writes sample k of strip s; returns the energy budget's state-and-work sum, so
        # the caller can stop a strip whose energy is not finite.
        n = model.n_nodes
        t = scalar(step - stepping.release_step) * stepping.dt
        m_node = model.node_mass[s]
        kinetic = zero
        gravitational = zero
        for i in range(model.n_clamped, n):
            m = m_node
            if i == n - 1:
                m = half * m_node
            v = state.velocity[i, s]
            kinetic = kinetic + half * m * wp.dot(v, v)
            gravitational = gravitational + m * model.gravity * state.position[i, s][1]
        tensile = zero
        a = model.tensile[s]
        for i in range(model.n_clamped - 1, n - 1):
            length = wp.length(state.position[i + 1, s] - state.position[i, s])
            strain = (length - model.rest_length) / model.rest_length
            tensile = tensile + tensile_energy(strain, a) * model.width[s] * model.rest_length
        theta, rate = clamp_angle(control, s, t)
        tip = state.position[n - 1, s]
        probes[k, TIP_X, s] = tip[0]
        probes[k, TIP_Y, s] = tip[1]
        probes[k, TIP_SPEED, s] = wp.length(state.velocity[n - 1, s])
        probes[k, LASER_X, s] = laser_crossing(model, state, s, settings.laser_height)
        probes[k, CLAMP_ANGLE, s] = theta
        probes[k, KINETIC, s] = kinetic
        probes[k, GRAVITATIONAL, s] = gravitational
        probes[k, TENSILE, s] = tensile
        # The loop hinge's curvature at the last force evaluation and the moment per
        # width there, read back from its memory (no extra force pass).
        # The memory holds K − K_rest (the law's argument); the probe is the strip's own K.
        memory = state.hinge[settings.loop_hinge, s]
        p = model.bending[s]
        curvature = law.last_curvature(memory)
        rest = model.rest_curvature[settings.loop_hinge, s]
        grip = model.grip[settings.loop_hinge, s]
        if rest != zero:  # adding 0 would turn a −0 curvature into +0
            probes[k, LOOP_CURVATURE, s] = curvature + rest
        else:
            probes[k, LOOP_CURVATURE, s] = curvature
        probes[k, LOOP_MOMENT, s] = (
            law.elastic_moment(curvature, p) * grip[0] + law.hysteretic_moment(curvature, memory, p) * grip[1]
        )
        return record_work(probes, k, s, state.work[s], kinetic + gravitational + tensile)

    return SimpleNamespace(ProbeSettings=ProbeSettings, record_probes=record_probes)
