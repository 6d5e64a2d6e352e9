"""``integrator.dt_s = "auto"``: the longest step the scheme runs stably and the evidence
says is accurate, a whole fraction of the probe interval (docs/model.md §9.6).

The step is the smallest of three, over every scene that shares it (a sweep's variants of
one scheme and probe interval, a fit's corners): a margin under the scheme's stability bound (exact for stretching,
:data:`STABILITY_MARGIN`), the longest step measured accurate for the scheme
(:data:`ACCURATE_STEP_S`), and the probe interval; then shortened so that a whole number
of steps fills the interval, so every probe falls on a step.

:func:`check_step` is here too: the checks of a scene about to run, its step's stability
among them (docs/model.md §9.3), and that a step auto chose was chosen for this scene.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

from warpcloth.errors import SceneError
from warpcloth.kernels import bending_law
from warpcloth.strip import SOLVERS, MaterialSI
from warpcloth.strip.solvers import StepBound
from warpcloth.strip.stability import cycle_response
from warpcloth.units import check_plausible

from .grip import grip_of
from .materials import to_si
from .schema import AUTO, Scene
from .validate import validate_scene

STABILITY_MARGIN = {True: 0.9, False: 0.8}
"""The fraction of the stability bound taken: 0.9 of an exact bound (strain and damping
lower the stretching limit a little, §9.3), 0.8 of the linearised bending estimate (a
deflected strip is not straight; measured 12 % conservative on a hysteretic rotation and
within 3 % on elastic ones, §9.6)."""

ACCURATE_STEP_S = {"semi_implicit": None, "imex": 2e-4, "imex_trapezoidal": 5e-4}
"""The longest step each scheme is measured accurate at, where stability does not already
bound it (the tip's largest error over its excursion against the dt = 1e-7 s solution;
benchmarks/imex_defaults.py, benchmarks/RESULTS.md). imex: within 0.2 % at 2e-4 s on both
bundled experiments with masing (0.106 % on the swing at h = 5 mm, 0.129 % on the rotation
at 2.5 mm) and on the elastic swing (0.15 %); its error grows as dt. imex_trapezoidal:
within 0.2 % at 5.56e-4 s on the elastic swing (0.185 %; masing 0.070 %), and on the
rotation stability binds first; on the bundled sweep's corners with masing 0.038 % at
4.17e-4 s. semi_implicit: within 0.01 % at its stretching
limit on both (stability binds first)."""

WITHOUT_RETURN_POINT_MEMORY = {"imex_trapezoidal": 1.12e-4}
"""The longest step an implicit scheme that auto accepts for a hysteretic law without
return-point memory (tagawa2003, dahl) is measured accurate at with it (docs/model.md
§9.5.1). imex_trapezoidal: the bundled sweep's 200 variants with the paper's law (1.3 s
hold, 3 s swing), worst 0.162 % at 1.11e-4 s (1/15 of 1/600 s), 0.168 % at 1.04e-4 s, 0.363 %
at 2.08e-4 s; the rotation 0.185 % and the swing 0.051 % at 1.11e-4 s, but the rotation
0.222 % at 1.19e-4 s. Not monotone in dt: the law integrates the total variation of the motion, and
the trapezoidal rule's stretching vibrations are not the explicit solution's (the rotation
is 0.306 % off at 5.2e-5 s). imex, whose floor is 0.4–2 %, is refused."""


@dataclass(frozen=True)
class StepChoice:
    """The chosen step and what set it."""

    dt_s: float
    bound: StepBound
    margin: float
    accurate_s: float | None
    interval_s: float
    scheme: str
    memoryless_laws: str | None = None  # laws without return-point memory that set a shorter accurate step

    def describe(self) -> str:
        """One line for the run's output."""
        held = (
            f"{self.margin:g} × the {self.bound.mode} {'limit' if self.bound.exact else 'estimate'} "
            f"{self.bound.seconds:.3e} s"
        )
        if self.accurate_s is not None:
            held += f" and the {self.accurate_s:g} s up to which {self.scheme} is measured within 0.2 %"
            if self.memoryless_laws:
                held += f" with the {self.memoryless_laws} law, which has no return-point memory"
        sections = "§9.5.1, §9.6" if self.memoryless_laws else "§9.6"
        return (
            f"integrator.dt_s = auto: {self.dt_s:.4e} s = 1/{round(self.interval_s / self.dt_s)} of the probe "
            f"interval, within {held} (docs/model.md {sections})"
        )


def _requests(scene: Scene) -> bool:
    return scene.integrator.dt_s == AUTO


def choose_step(scenes: Sequence[Scene]) -> StepChoice:
    """The step for ``scenes`` (one scheme and probe interval: batch fields), the longest
    that suits every one; a SceneError of ``integrator.dt_s`` where there is no such step."""
    first = scenes[0]
    scheme, interval = first.integrator.scheme, first.output_interval
    materials = [to_si(scene.material) for scene in scenes]
    response = cycle_response(materials)
    memoryless = set()  # the scenes' hysteretic laws without return-point memory
    for scene, material, (_, loop) in zip(scenes, materials, response, strict=True):
        law = bending_law(material.bending_law)
        if loop > 0 and not law.mesh_independent and scheme in WITHOUT_RETURN_POINT_MEMORY:
            memoryless.add(law.name)
        if scheme == "imex" and loop > 0 and not law.mesh_independent:
            raise SceneError(
                "integrator.dt_s",
                f"auto has no accurate imex step for the {law.name} law of "
                f"material {scene.material.name!r}: without return-point memory its loop keeps a "
                "0.1–2 % floor against the converged solution that no dt removes (docs/model.md "
                '§9.5); use scheme = "imex_trapezoidal" (§9.5.1), '
                'bending_law = "masing", or scheme = "semi_implicit" with dt_s = "auto"',
                related=("integrator.scheme", "material.bending_law"),
            )
    bounds = []
    for scene, material in zip(scenes, materials, strict=True):
        bound = _stability_bound(scene, material)
        if bound is None:
            raise SceneError(
                "integrator.dt_s",
                f"auto needs a scheme with a known stability limit; {scheme} has "
                "none (forward Euler amplifies every undamped oscillation, docs/model.md §9): use "
                "semi_implicit or imex",
                related=("integrator.scheme",),
            )
        bounds.append(bound)
    bound = min(bounds, key=lambda b: b.seconds * STABILITY_MARGIN[b.exact])
    margin = STABILITY_MARGIN[bound.exact]
    accurate = WITHOUT_RETURN_POINT_MEMORY[scheme] if memoryless else ACCURATE_STEP_S.get(scheme)
    longest = min(bound.seconds * margin, accurate or math.inf, interval)
    dt = interval / math.ceil(interval / longest * (1 - 1e-12))
    return StepChoice(
        dt,
        bound,
        margin,
        accurate if accurate is not None and accurate < bound.seconds * margin else None,
        interval,
        scheme,
        ", ".join(sorted(memoryless)) or None,
    )


def with_chosen_step(scenes: Sequence[Scene]) -> list[Scene]:
    """``scenes`` with every ``dt_s = "auto"`` replaced by the one step
    :func:`choose_step` picks for all of them, marked ``dt_chosen_by = "auto"``; scenes
    with a number keep it. The choice is made per group of scheme and probe interval."""
    scenes = list(scenes)
    groups: dict[tuple[str, float], list[int]] = {}
    for i, scene in enumerate(scenes):
        if _requests(scene):
            groups.setdefault((scene.integrator.scheme, scene.output_interval), []).append(i)
    for members in groups.values():
        dt = choose_step([scenes[i] for i in members]).dt_s
        for i in members:
            integrator = dataclasses.replace(scenes[i].integrator, dt_s=dt, dt_chosen_by=AUTO)
            scenes[i] = dataclasses.replace(scenes[i], integrator=integrator)
            validate_scene(scenes[i])  # the checks that needed a number (steps in the run)
    return scenes


def shared_auto_step(scenes: Sequence[Scene]) -> list[Scene]:
    """``scenes`` for one batch: those whose step auto chose (``dt_chosen_by = "auto"``),
    each alone, get the one step that suits them all when theirs differ, and a scene that
    still asks for ``dt_s = "auto"`` gets it chosen; the rest as given."""
    scenes = with_chosen_step(scenes)
    chosen = [i for i, s in enumerate(scenes) if s.integrator.dt_chosen_by == AUTO]
    if len({scenes[i].integrator.dt_s for i in chosen}) > 1:
        for i, scene in zip(chosen, with_chosen_step(requesting_auto([scenes[i] for i in chosen])), strict=True):
            scenes[i] = scene
    return scenes


def check_chosen_step(scene: Scene) -> None:
    """Refuse a step that ``dt_s = "auto"`` chose for another scene: a recorded scene
    (``dt_chosen_by = "auto"``) whose spacing, material or scheme was changed since, so its
    number is longer than auto would choose for it now. (A step shared with other scenes,
    a sweep's or a fit's, is never longer than this scene's own.)"""
    if scene.integrator.dt_chosen_by != AUTO or isinstance(scene.integrator.dt_s, str):
        return
    now = choose_step(requesting_auto([scene])).dt_s
    if scene.integrator.dt_s > now * (1 + 1e-9):
        raise SceneError(
            "integrator.dt_s",
            f'{scene.integrator.dt_s:.4e} s was chosen by dt_s = "auto" for '
            f'another scene (integrator.dt_chosen_by = "auto"); for this one auto chooses '
            f'{now:.4e} s: set integrator.dt_s = "auto" to choose again, or give the step with '
            'integrator.dt_chosen_by = "scene"',
            related=("integrator.dt_chosen_by", "strip.spacing_mm", "integrator.scheme"),
        )


def _stability_bound(scene: Scene, material: MaterialSI) -> StepBound | None:
    return SOLVERS[scene.integrator.scheme].stable_step(
        material,
        scene.spacing,
        scene.n_nodes - scene.n_clamped,
        scene.edge_hinge_length,
        scene.run.gravity_m_per_s2,
        grip_of(scene),
    )


def stable_step_of(scene: Scene) -> float | None:
    """The longest step the scene's scheme runs stably with auto's margin (s), None for
    a scheme without a known bound."""
    bound = _stability_bound(scene, to_si(scene.material))
    return None if bound is None else bound.seconds * STABILITY_MARGIN[bound.exact]


def requesting_auto(scenes: Sequence[Scene]) -> list[Scene]:
    """``scenes`` as if each asked for ``dt_s = "auto"`` again (to say why a step was chosen)."""
    return [dataclasses.replace(s, integrator=dataclasses.replace(s.integrator, dt_s=AUTO)) for s in scenes]


def describe_step(scene: Scene) -> str:
    """What auto chooses for ``scene`` alone and why: the line ``run`` prints for a step
    chosen automatically (a sweep's or a fit's step suits all its scenes, and may be shorter)."""
    choice = choose_step(requesting_auto([scene]))
    if math.isclose(choice.dt_s, scene.integrator.dt_s, rel_tol=1e-12):
        return choice.describe()
    return (
        f"integrator.dt_s = auto: {scene.integrator.dt_s:.4e} s, the longest step that suits every scene "
        f"sharing it (this one alone: {choice.describe().split(': ', 1)[1]})"
    )


STEP_LIMIT_SLACK = 1e-3
"""With a softening tensile law (a negative a2..a4), a step is refused only this far
(relative) above the scheme's limit: strained by the hang, such a law can raise the
true limit by up to ~5e-4. Without one, the limit is exact and a step above it is
refused."""


def check_step(scene: Scene) -> None:
    """Refuse a time step the scene's scheme cannot run stably (docs/model.md §9.3).

    Not part of :func:`validate_scene`: a recorded scene is read back as it was run (a
    diverged run stays readable); this check is for scenes about to run. So are two more:
    a laser line the hanging strip never crosses is refused (its record would be the free
    end's, not the laser's), and an implausible density is warned about
    (:func:`warpcloth.units.check_plausible`).
    """
    st = scene.strip
    if not -st.free_length_mm < scene.output.laser_height_mm < 0:
        raise SceneError(
            "output.laser_height_mm",
            f"{scene.output.laser_height_mm:g} mm is not on the hanging "
            f"strip, which reaches from 0 to -{st.free_length_mm:g} mm (strip.free_length_mm): the "
            f"laser line would never cross it; put it between -{st.free_length_mm:g} and 0 mm",
            related=("strip.free_length_mm",),
        )
    check_plausible("areal density", scene.material.density_g_per_cm2, "material.density_g_per_cm2")
    check_chosen_step(scene)
    dt, scheme = scene.integrator.dt_s, scene.integrator.scheme
    limit = SOLVERS[scheme].step_limit(to_si(scene.material), scene.spacing, scene.n_nodes - scene.n_clamped)
    softening = any(a < 0 for a in scene.material.tensile_gf_per_cm[1:])
    if limit is None or dt <= limit * (1 + (STEP_LIMIT_SLACK if softening else 0.0)):
        return
    m, st = scene.material, scene.strip
    unit = 10.0 ** (math.floor(math.log10(limit)) - 3)
    below = math.floor(limit / unit) * unit  # 4 digits, rounded down: the advice itself runs
    raise SceneError(
        "integrator.dt_s",
        f"{dt:g} s is above the {scheme} scheme's stability limit {below:.3e} s "
        f"for this strip: the stretching mode, h·√(ρ_A/a1)/cos(π/4N) with strip.spacing_mm = "
        f"{st.spacing_mm:g} (N = {scene.n_nodes - scene.n_clamped} free nodes), "
        f"material.density_g_per_cm2 = {m.density_g_per_cm2:g}, material.tensile_gf_per_cm[0] = "
        f"{m.tensile_gf_per_cm[0]:g}; use a dt_s of at most {below:.3e} s or integrator.scheme = "
        '"imex" (stretching implicit)',
        related=(
            "strip.spacing_mm",
            "strip.free_length_mm",
            "material.density_g_per_cm2",
            "material.tensile_gf_per_cm",
            "material.from_file",
            "integrator.scheme",
        ),
    )


def checked_step(scene: Scene) -> Scene:
    """``scene``, after :func:`check_step` found it runnable (the strip's ``check_scene``
    hook in :mod:`warpcloth.bodies`)."""
    check_step(scene)
    return scene
