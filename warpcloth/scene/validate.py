"""Cross-field checks of a parsed scene that single fields cannot express."""

from __future__ import annotations

import math

from warpcloth import units
from warpcloth.core.resources import duration_text
from warpcloth.errors import SceneError

from .materials import validate_material
from .schema import AUTO, ClampSection, ReleaseSection, Scene

MAX_STEPS = 2**31 - 1
MAX_NODES = 2**31 - 1
"""Nodes of one strip at most: what a kernel's 32-bit index reaches (the memory check of
:func:`warpcloth.scene.build.builder_for` refuses far fewer on a real machine)."""


MAX_HELD_SAG = 0.1
"""The most a held strip's slack may sag below its held end, as a part of its length (a
hanging chain's, which a strip with bending rigidity sags less than): more is a fold."""
TAUT_HOLD = 0.94
"""The suggested held position's distance, as a part of the length, where it holds the
strip taut enough: the bundled damped_swing's (94.3 mm of 100), whose slack sags nowhere
below the held end (:func:`taut_distance` goes farther where this is not enough)."""


def taut_distance(ux: float, uy: float, length_mm: float) -> float:
    """How far from the clamp, along the unit direction (``ux``, ``uy``), to hold the free end
    of a strip of ``length_mm`` so that it sags at most half of :data:`MAX_HELD_SAG` of its
    length (a margin for the rounding of a suggested position): :data:`TAUT_HOLD` of the
    length where that is enough, else the nearest such distance (at the full length the
    chain is straight and sags nothing), found by bisection."""
    limit = 0.5 * MAX_HELD_SAG * length_mm
    near, far = TAUT_HOLD * length_mm, length_mm
    if hanging_sag(ux * near, uy * near, length_mm) <= limit:
        return near
    for _ in range(60):
        middle = 0.5 * (near + far)
        if hanging_sag(ux * middle, uy * middle, length_mm) <= limit:
            far = middle
        else:
            near = middle
    return far


def hanging_sag(x_mm: float, y_mm: float, length_mm: float) -> float:
    """How far below the point (``x_mm``, ``y_mm``) (y up, from the clamp's lowest point) a
    hanging chain of ``length_mm`` from the clamp to that point sags, mm: 0 when its
    lowest point is an end. The catenary through both ends (span x, height difference y)
    has parameter a with 2a·sinh(x / 2a) = √(L² − y²) and its vertex at
    x/2 − a·atanh(y / L) from the clamp; a vertex between the ends is a sag below them."""
    from scipy.optimize import brentq

    span = abs(x_mm)
    chord = math.sqrt(max(length_mm**2 - y_mm**2, 0.0))
    if chord <= span:
        return 0.0
    if span < 1e-9 * length_mm:  # held straight below: the slack folds down and back up
        return max((length_mm + y_mm) / 2, 0.0)
    u = brentq(lambda u: math.sinh(u) / u - chord / span, 1e-9, 700.0)  # u = span / 2a
    a = span / (2 * u)
    vertex = span / 2 - a * math.atanh(y_mm / length_mm)
    return a * (math.cosh((span - vertex) / a) - 1) if 0 < vertex < span else 0.0


def _multiple(length: float, spacing: float) -> bool:
    ratio = length / spacing
    return abs(ratio - round(ratio)) < 1e-9 * max(1.0, ratio)


def validate_scene(scene: Scene) -> None:
    """Cross-field checks that single fields cannot express; raises SceneError."""
    st = scene.strip
    # in floats, before any count is rounded to an integer (a length of 1e308 mm is inf nodes)
    nodes = st.clamp_length_mm / st.spacing_mm + st.free_length_mm / st.spacing_mm
    if not nodes <= MAX_NODES:
        raise SceneError(
            "strip.free_length_mm",
            f"{st.free_length_mm:g} mm below and strip.clamp_length_mm = "
            f"{st.clamp_length_mm:g} mm in the clamp at strip.spacing_mm = {st.spacing_mm:g} mm are "
            f"{nodes:.3g} nodes, more than {MAX_NODES}",
            related=("strip.clamp_length_mm", "strip.spacing_mm"),
        )
    for name in ("free_length_mm", "clamp_length_mm"):
        if not _multiple(getattr(st, name), st.spacing_mm):
            raise SceneError(
                "strip.spacing_mm",
                f"{st.spacing_mm:g} mm does not divide strip.{name} = {getattr(st, name):g} mm into whole segments",
                related=(f"strip.{name}",),
            )
    if scene.n_nodes - scene.n_clamped < 2:
        raise SceneError(
            "strip.spacing_mm",
            f"{st.spacing_mm:g} mm leaves fewer than 2 free nodes",
            related=("strip.free_length_mm",),
        )
    validate_material(scene.material, scene.integrator.divergence_strain, "material")
    _validate_clamp(scene.clamp)
    _validate_rest_curvature(scene)
    _validate_grip(scene)
    if not scene.release.hold_free_end:
        if not scene.release.enabled:
            raise SceneError(
                "release.hold_free_end",
                "= false but release.enabled = false: there is no pre-roll "
                "for the free end to settle in, so it would be ignored; remove it or enable the release",
                related=("release.enabled",),
            )
        defaults = ReleaseSection()
        for name in ("hold_x_mm", "hold_y_mm"):
            if getattr(scene.release, name) != getattr(defaults, name):
                raise SceneError(
                    f"release.{name}",
                    f"= {getattr(scene.release, name):g} mm but "
                    "release.hold_free_end = false leaves the free end free, so no held position is "
                    "used; remove it or hold the free end",
                    related=("release.hold_free_end",),
                )
    if scene.release.enabled and scene.release.hold_free_end:
        r = math.hypot(scene.release.hold_x_mm, scene.release.hold_y_mm)
        if not st.spacing_mm <= r <= st.free_length_mm:
            raise SceneError(
                "release.hold_x_mm",
                f"held position ({scene.release.hold_x_mm:g}, "
                f"{scene.release.hold_y_mm:g}) mm is {r:g} mm from the clamp's lowest point; "
                f"the free end reaches between {st.spacing_mm:g} and {st.free_length_mm:g} mm",
                related=("release.hold_y_mm", "strip.free_length_mm", "strip.spacing_mm"),
            )
        sag = hanging_sag(scene.release.hold_x_mm, scene.release.hold_y_mm, st.free_length_mm)
        if sag > MAX_HELD_SAG * st.free_length_mm and not scene.release.allow_fold:
            reach = taut_distance(scene.release.hold_x_mm / r, scene.release.hold_y_mm / r, st.free_length_mm)
            x, y = (v * reach / r for v in (scene.release.hold_x_mm, scene.release.hold_y_mm))
            raise SceneError(
                "release.hold_x_mm",
                f"the free end held at ({scene.release.hold_x_mm:g}, {scene.release.hold_y_mm:g}) mm, {r:.3g} mm "
                f"from the clamp's lowest point, leaves {st.free_length_mm - r:.3g} mm of the {st.free_length_mm:g} "
                f"mm strip slack: hanging, it sags {sag:.3g} mm below the held end (more than "
                f"{MAX_HELD_SAG:.0%} of its length), so the swing would start from a fold, not an arc; hold it "
                f"farther out, e.g. at ({x:.4g}, {y:.4g}) mm (the same direction, "
                f"{reach / st.free_length_mm:.3g} of the length away), "
                "or set release.allow_fold = true to start from the fold on purpose",
                related=("release.hold_y_mm", "strip.free_length_mm", "release.allow_fold"),
            )
    n_hinges = scene.n_nodes - scene.n_clamped
    if not _multiple(scene.output.loop_hinge_mm, st.spacing_mm) or scene.loop_hinge >= n_hinges:
        raise SceneError(
            "output.loop_hinge_mm",
            f"{scene.output.loop_hinge_mm:g} mm is not a hinge: hinges lie "
            f"every strip.spacing_mm = {st.spacing_mm:g} mm from 0 to "
            f"{st.free_length_mm - st.spacing_mm:g} mm below the clamp",
            related=("strip.spacing_mm", "strip.free_length_mm"),
        )
    dt = scene.integrator.dt_s
    if isinstance(dt, str):  # "auto", chosen after these checks (warpcloth.scene.step)
        return
    if dt > scene.output_interval:
        raise SceneError(
            "integrator.dt_s",
            f"{dt:g} s is longer than the probe interval "
            f"{scene.output_interval:g} s (1 / (output.frame_rate_hz × output.probes_per_frame))",
            related=("output.frame_rate_hz", "output.probes_per_frame"),
        )
    check_step_count(
        scene.preroll + scene.run.duration_s,
        scene.integrator,
        scene.n_nodes,
        "strip",
        ("run.duration_s", "release.settle_time_s", "release.move_time_s", "strip.spacing_mm"),
    )


def check_step_count(total_s: float, integrator: object, n_nodes: int, body: str, related: tuple[str, ...]) -> None:
    """Refuse, naming ``integrator.dt_s`` (``run.duration_s`` for a record longer than
    any swing is measured for), a run whose step count (``total_s`` of
    settling and record at the integrator's step) is beyond ``integrator.max_steps``
    (what a kernel counts at most, :data:`MAX_STEPS`, in any case), with its estimated
    time on one CPU core: a step that collapsed under a stiffness or spacing beyond
    reason would otherwise run for hours without a word."""
    from warpcloth import bodies

    if integrator.max_steps > MAX_STEPS:
        raise SceneError("integrator.max_steps", f"{integrator.max_steps} is more than a kernel counts ({MAX_STEPS})")
    dt = integrator.dt_s
    steps = total_s / dt
    if steps <= integrator.max_steps:
        return
    ns = bodies.named(body).cpu_ns_per_node_step
    chosen = (
        ' (chosen by dt_s = "auto": the stiffest element allows no longer)' if integrator.dt_chosen_by == AUTO else ""
    )
    # the field to blame: a record longer than any swing is measured for, else the step
    long_record = total_s > units.PLAUSIBLE["record length"][1]
    cause = (
        "a record longer than any swing is measured for"
        if long_record
        else "a step this short comes from a stiffness or spacing beyond reason"
    )
    raise SceneError(
        "run.duration_s" if long_record else "integrator.dt_s",
        f"{total_s:g} s of settling and record at dt = {dt:.4g} s{chosen} is {steps:.3g} steps of each {body}, more "
        f"than integrator.max_steps = {integrator.max_steps}: about {duration_text(steps * n_nodes * ns * 1e-9)} "
        f"of a CPU core per {body} ({n_nodes} nodes at ~{ns:g} ns a node-step); {cause}; raise "
        "integrator.max_steps to run it on purpose",
        related=("integrator.dt_s", *related) if long_record else related,
    )


def _validate_rest_curvature(scene: Scene) -> None:
    st = scene.strip
    s, k = st.rest_curvature_table_s_mm, st.rest_curvature_table_per_cm
    if s or k:
        if st.rest_curvature_per_cm != 0.0:
            raise SceneError(
                "strip.rest_curvature_per_cm",
                f"= {st.rest_curvature_per_cm:g} 1/cm and a table "
                "strip.rest_curvature_table_per_cm are both given; give the constant or the table",
                related=("strip.rest_curvature_table_per_cm",),
            )
        if len(s) < 2 or len(s) != len(k):
            raise SceneError(
                "strip.rest_curvature_table_per_cm",
                f"needs as many values as "
                f"strip.rest_curvature_table_s_mm, at least 2 (got {len(s)} arc lengths and {len(k)} "
                "curvatures)",
                related=("strip.rest_curvature_table_s_mm",),
            )
        if s[0] != 0.0:
            raise SceneError(
                "strip.rest_curvature_table_s_mm[0]",
                f"{s[0]:g} mm must be 0 (the clamp's lowest point): the profile covers the whole free strip",
            )
        for i in range(1, len(s)):
            if not s[i] > s[i - 1]:
                raise SceneError(f"strip.rest_curvature_table_s_mm[{i}]", f"{s[i]:g} mm must be after {s[i - 1]:g} mm")
        if s[-1] < st.free_length_mm:
            raise SceneError(
                f"strip.rest_curvature_table_s_mm[{len(s) - 1}]",
                f"{s[-1]:g} mm ends above the free "
                f"end; the profile must reach strip.free_length_mm = {st.free_length_mm:g} mm",
                related=("strip.free_length_mm",),
            )
    # a hinge turns by about K h between its segments; beyond 1/h the chain folds (§5.4)
    limit = 10.0 / st.spacing_mm  # 1/h in 1/cm
    for name, values in (("rest_curvature_per_cm", [st.rest_curvature_per_cm]), ("rest_curvature_table_per_cm", k)):
        for i, value in enumerate(values):
            if abs(value) > limit:
                where = f"strip.{name}" + (f"[{i}]" if name.endswith("table_per_cm") else "")
                raise SceneError(
                    where,
                    f"{value:g} 1/cm curls the strip by more than one radian per segment "
                    f"(1/h = {limit:g} 1/cm at strip.spacing_mm = {st.spacing_mm:g}); a fabric's set "
                    "is far gentler, or refine the spacing",
                    related=("strip.spacing_mm",),
                )


def _validate_grip(scene: Scene) -> None:
    # a zone of length 0 has no effect whatever its factors: the limit a fit of ℓ_g crosses
    clamp, st = scene.clamp, scene.strip
    if clamp.grip_length_mm > st.free_length_mm:
        raise SceneError(
            "clamp.grip_length_mm",
            f"{clamp.grip_length_mm:g} mm is longer than the free strip "
            f"(strip.free_length_mm = {st.free_length_mm:g} mm)",
            related=("strip.free_length_mm",),
        )


def _validate_clamp(clamp: ClampSection) -> None:
    # a motion given to a clamp that stays fixed would be ignored in silence (motion
    # forgotten); switching between piecewise and table may leave the other's fields
    if clamp.motion == "fixed":
        for name, needs in (("segments", "piecewise"), ("table_t_s", "table"), ("table_theta_rad", "table")):
            if getattr(clamp, name):
                raise SceneError(
                    f"clamp.{name}",
                    f"is given but clamp.motion = 'fixed' ignores it; set motion = \"{needs}\" or remove it",
                )
    if clamp.motion == "piecewise":
        if not clamp.segments:
            raise SceneError("clamp.segments", "motion = 'piecewise' needs at least one segment")
        validate_segments(clamp.segments, "clamp.segments", "theta_coefficients_si", "θ", "rad")
    elif clamp.motion == "table":
        t, th = clamp.table_t_s, clamp.table_theta_rad
        if len(t) < 2 or len(t) != len(th):
            raise SceneError(
                "clamp.table_theta_rad",
                f"needs as many samples as clamp.table_t_s, at least 2 (got {len(t)} times and {len(th)} angles)",
            )
        for i in range(1, len(t)):
            if not t[i] > t[i - 1]:
                raise SceneError(f"clamp.table_t_s[{i}]", f"{t[i]:g} s must be after {t[i - 1]:g} s")


def validate_segments(segments: list, prefix: str, coefficients: str, symbol: str, unit: str) -> None:
    """Pieces of a clamp motion (the strip's θ, the sheet's rotation and translation):
    each ends after it starts, holds 1 to 5 coefficients (its attribute ``coefficients``),
    starts where the previous ended and continues its value (``symbol`` in ``unit``)."""
    for i, seg in enumerate(segments):
        where = f"{prefix}[{i}]"
        values = getattr(seg, coefficients)
        if not seg.t_end_s > seg.t_start_s:
            raise SceneError(f"{where}.t_end_s", f"{seg.t_end_s:g} must be after t_start_s {seg.t_start_s:g}")
        if not 1 <= len(values) <= 5:
            raise SceneError(
                f"{where}.{coefficients}",
                f"needs 1 to 5 coefficients (up to a quartic), got {len(values)}",
            )
        if i:
            prev = segments[i - 1]
            if abs(seg.t_start_s - prev.t_end_s) > 1e-12:
                raise SceneError(
                    f"{where}.t_start_s",
                    f"{seg.t_start_s:g} s must equal the previous segment's t_end_s {prev.t_end_s:g} s",
                )
            tau = prev.t_end_s - prev.t_start_s
            end = sum(c * tau**k for k, c in enumerate(getattr(prev, coefficients)))
            jump = values[0] - end
            if abs(jump) > 1e-9 * max(1.0, abs(end)):
                raise SceneError(
                    f"{where}.{coefficients}",
                    f"{symbol} jumps by {jump:.3g} {unit} at t = {seg.t_start_s:g} s; the clamp "
                    "cannot teleport (make c_0 equal the previous segment's end value)",
                )
