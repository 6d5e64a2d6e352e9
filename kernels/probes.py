"""What is recorded of every strip at each output sample (docs/model.md §12).

The probe buffer is ``[sample, field, strip]`` with fields in :data:`PROBE_FIELDS`
order; the kernel writes each field through its named slot, so adding a probe is one
name and its unit here and one line in ``record_probes``.
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import drives, integrators, structs, tensile

PROBE_FIELDS = (
    "tip_x",
    "tip_y",
    "tip_speed",
    "laser_x",
    "clamp_angle",
    "kinetic",
    "gravitational",
    "tensile",
    "bending_elastic_work",
    "hysteresis_work",
    "damping_work",
    "drive_work",
    "loop_curvature",
    "loop_moment",
)
"""Probe quantities, in the order of the probe buffer's second axis (SI)."""

PROBE_INDEX = {name: i for i, name in enumerate(PROBE_FIELDS)}
"""Slot of each probe quantity."""

PROBE_UNITS = {
    "tip_x": "m",
    "tip_y": "m",
    "tip_speed": "m/s",
    "laser_x": "m (NaN when the strip misses the line)",
    "clamp_angle": "rad",
    "kinetic": "J",
    "gravitational": "J",
    "tensile": "J",
    "bending_elastic_work": "J",
    "hysteresis_work": "J",
    "damping_work": "J",
    "drive_work": "J",
    "loop_curvature": "1/m (output.loop_hinge_mm)",
    "loop_moment": "N·m/m (moment per width)",
}
"""SI unit of each probe quantity, as written into a run directory's meta.json."""


@functools.cache
def build(scalar: Any) -> SimpleNamespace:
    """The ``ProbeSettings`` struct and ``record_probes`` for ``scalar``."""
    zero = scalar(0.0)
    half = scalar(0.5)
    strip = structs.build(scalar)
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
    BENDING_ELASTIC_WORK, HYSTERESIS_WORK = slot.bending_elastic_work, slot.hysteresis_work
    DAMPING_WORK, DRIVE_WORK = slot.damping_work, slot.drive_work
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
        work = state.work[s]
        probes[k, TIP_X, s] = tip[0]
        probes[k, TIP_Y, s] = tip[1]
        probes[k, TIP_SPEED, s] = wp.length(state.velocity[n - 1, s])
        probes[k, LASER_X, s] = laser_crossing(model, state, s, settings.laser_height)
        probes[k, CLAMP_ANGLE, s] = theta
        probes[k, KINETIC, s] = kinetic
        probes[k, GRAVITATIONAL, s] = gravitational
        probes[k, TENSILE, s] = tensile
        probes[k, BENDING_ELASTIC_WORK, s] = work[0]
        probes[k, HYSTERESIS_WORK, s] = work[1]
        probes[k, DAMPING_WORK, s] = work[2]
        probes[k, DRIVE_WORK, s] = work[3]
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
        return kinetic + gravitational + tensile + work[0] + work[1] + work[2]

    return SimpleNamespace(ProbeSettings=ProbeSettings, record_probes=record_probes)
