"""The bodies warpcloth simulates, in one registry: the strip and the woven sheet.

Everything that depends on which body a scene, a run directory or a measurement is about
asks here instead of branching on it: the scene loader (:func:`of_data`), runs
(:func:`of_scene`), sweeps, fits, run directories (:func:`of_run`) and the command line.
A body is a name and its hooks, each a ``"module:attribute"`` resolved on first use, so
this module imports nothing of warpcloth and any layer may consult it. Adding a body is
its package (model, state, control, solver, recorder on :mod:`warpcloth.core`), its scene
section, and one entry here (docs/architecture.md counts the files).
"""

from __future__ import annotations

import importlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HOOKS = {
    "scene_type": "the body's scene class",
    "own_sections": "raw scene data → the sections and fields only this body has (a file without its table "
    "that gives them is refused)",
    "scene_from_dict": "raw scene data → a validated scene (data, choose_step=True)",
    "check_scene": "a validated scene → the scene checked runnable (its step within the stability bound)",
    "sweep_variant": "raw data of one sweep variant → its scene, the step not yet chosen",
    "sweep_ready": "(variant scenes, assignments) → the scenes ready to run, one step per batch",
    "batch_key": "a scene → what variants sharing one launch sequence must agree on",
    "build": "(scenes, device=None, terms=()) → the batch's model, control, solver and recorder",
    "simulate": "(scenes, **options) → RunResult: the batch run, streamed to out= when given",
    "sweep_batch": "(scenes or their dicts, device, frames) → a sweep batch's probe store rows and summary",
    "warm": "(scenes, device) → compile the kernels a sweep's workers will load",
    "sweep_steps": "a sweep → the lines `warpcloth sweep` prints of the steps auto chose",
    "sweep_warnings": "a sweep's summary → the warnings `warpcloth sweep` prints of it",
    "memory_bytes": "(scene, frames) → memory one variant's record takes while its batch runs",
    "disk_bytes": "(scene, frames, probes) → bytes one variant's files take in a sweep directory",
    "summary_probes": "a scene → the probe store's columns its summary is measured from (`sweep --probes summary`)",
    "coordinates": "the frame of every position a run stores (a string)",
    "read_run": "a run directory → what was recorded (the body's reader)",
    "objective": "(base, measurement, free, align_start_s, device) → the fit's objective",
    "read_measurement": "(path, argument=) → the measurement a fit of the body takes",
    "free_parameters": "(names, scene, bounds) → the fit's free parameters",
    "describe_step": "a scene whose step auto chose → the sentence `warpcloth run` prints of it",
    "summary": "(scene, result) → the lines `warpcloth run` prints after the run",
    "export_usd": "(run directory, stage file) → the USD stage `warpcloth run --usd` writes",
    "usd_command": "`warpcloth export-usd` of a run directory (args → exit code)",
    "plot_command": "`warpcloth plot` of a run directory (args → exit code)",
    "render": "`warpcloth render` of a run directory (args → the files written)",
}
"""What every body provides, by hook name."""


@dataclass(frozen=True)
class Body:
    """One body: its ``name`` (a scene's table, a run's meta.json ``kind``), the unit its
    throughput is counted in, what a node-step costs one CPU core (ns, measured: the
    estimate a run too long to start is refused with), and its :data:`HOOKS` as
    ``"module:attribute"``."""

    name: str
    steps: str
    cpu_ns_per_node_step: float
    hooks: dict[str, str]

    def hook(self, name: str) -> Any:
        """The object hook ``name`` names (imported on first use)."""
        return _resolve(self.hooks[name])

    def __call__(self, name: str, *args: Any, **kwargs: Any) -> Any:
        """Call hook ``name`` with the arguments given."""
        return self.hook(name)(*args, **kwargs)


def _resolve(target: str) -> Any:
    module, _, attribute = target.partition(":")
    return getattr(importlib.import_module(module), attribute)


BODIES: dict[str, Body] = {
    "strip": Body(
        "strip",
        "strip-steps",
        40.0,  # damped_swing, one core of the 2-core CI machine (benchmarks/RESULTS.md: 28-45 ns)
        {
            "scene_type": "warpcloth.scene.schema:Scene",
            "own_sections": "warpcloth.scene.files:strip_sections",
            "scene_from_dict": "warpcloth.scene.files:strip_scene_from_dict",
            "check_scene": "warpcloth.scene.step:checked_step",
            "sweep_variant": "warpcloth.scene.sweep:strip_variant",
            "sweep_ready": "warpcloth.scene.sweep:strip_variants",
            "batch_key": "warpcloth.scene.sweep:strip_batch_key",
            "build": "warpcloth.scene.build:build_batch",
            "simulate": "warpcloth.runs:simulate_strip_scenes",
            "sweep_batch": "warpcloth.sweeps:strip_sweep_batch",
            "warm": "warpcloth.sweeps:warm_kernel_cache",
            "sweep_steps": "warpcloth.cli.sweep:strip_sweep_steps",
            "sweep_warnings": "warpcloth.cli.sweep:strip_sweep_warnings",
            "memory_bytes": "warpcloth.sweeps:strip_memory_bytes",
            "disk_bytes": "warpcloth.sweeps:strip_disk_bytes",
            "summary_probes": "warpcloth.sweeps:strip_summary_probes",
            "coordinates": "warpcloth.scene.geometry:COORDINATES",
            "read_run": "warpcloth.io.run_dir:read_run",
            "objective": "warpcloth.calibrate.motion_fit.objective:Objective",
            "read_measurement": "warpcloth.io.measured:read_measurement",
            "free_parameters": "warpcloth.calibrate.motion_fit.parameters:free_parameters",
            "describe_step": "warpcloth.scene.step:describe_step",
            "summary": "warpcloth.cli.run:strip_summary",
            "export_usd": "warpcloth.viz.usd:export_run_usd",
            "usd_command": "warpcloth.cli.view:strip_usd_command",
            "plot_command": "warpcloth.cli.view:strip_plot_command",
            "render": "warpcloth.cli.view:strip_render",
        },
    ),
    "sheet": Body(
        "sheet",
        "node-steps",
        170.0,  # shear_swing at 5 mm, one core of the 2-core CI machine
        {
            "scene_type": "warpcloth.scene.sheet:SheetScene",
            "own_sections": "warpcloth.scene.sheet:sheet_sections",
            "scene_from_dict": "warpcloth.scene.sheet:sheet_scene_from_dict",
            "check_scene": "warpcloth.scene.sheet_build:check_sheet_scene",
            "sweep_variant": "warpcloth.scene.sheet:sheet_scene_from_dict",
            "sweep_ready": "warpcloth.scene.sheet_build:sheet_variants",
            "batch_key": "warpcloth.scene.sheet_build:sheet_batch_key",
            "build": "warpcloth.scene.sheet_build:build_sheets",
            "simulate": "warpcloth.runs:simulate_sheet_scenes",
            "sweep_batch": "warpcloth.sweeps:sheet_sweep_batch",
            "warm": "warpcloth.sweeps:warm_sheet_kernel_cache",
            "sweep_steps": "warpcloth.cli.sheet:sheet_sweep_steps",
            "sweep_warnings": "warpcloth.cli.sheet:sheet_sweep_warnings",
            "memory_bytes": "warpcloth.sweeps:sheet_memory_bytes",
            "disk_bytes": "warpcloth.sweeps:sheet_disk_bytes",
            "summary_probes": "warpcloth.sweeps:sheet_summary_probes",
            "coordinates": "warpcloth.io.sheet_run_dir:SHEET_COORDINATES",
            "read_run": "warpcloth.io.sheet_run_dir:read_sheet_run",
            "objective": "warpcloth.calibrate.motion_fit.sheet:SheetObjective",
            "read_measurement": "warpcloth.io.measured:read_sheet_markers",
            "free_parameters": "warpcloth.calibrate.motion_fit.sheet:sheet_free_parameters",
            "describe_step": "warpcloth.scene.sheet_build:describe_sheet_step",
            "summary": "warpcloth.cli.sheet:sheet_summary",
            "export_usd": "warpcloth.viz.usd:export_sheet_run_usd",
            "usd_command": "warpcloth.cli.sheet:sheet_usd_command",
            "plot_command": "warpcloth.cli.sheet:sheet_plot_command",
            "render": "warpcloth.cli.sheet:sheet_render",
        },
    ),
}
"""Every body, by name."""


def named(name: str) -> Body:
    """The body called ``name``, or an ArgumentError listing them."""
    if name not in BODIES:
        from warpcloth.errors import ArgumentError

        raise ArgumentError("body", f"{name!r} is not a body warpcloth simulates; they are {', '.join(BODIES)}")
    return BODIES[name]


DEFAULT = "strip"
"""The body of a scene that names none: a file without a body's table is a strip with the
default geometry (an empty file is the documented defaults)."""


def of_data(data: dict, where: str = "the scene") -> Body:
    """The body raw scene ``data`` describes: the one whose table (its name: [strip],
    [sheet]) it has. Two tables, or none in a file that gives another body's own sections,
    is a SceneError naming ``where``."""
    from warpcloth.errors import SceneError

    tables = [name for name in BODIES if name in data]
    if len(tables) > 1:
        both = " and ".join(f"[{t}]" for t in tables)
        raise SceneError(tables[-1], f"{where} has both {both}; a scene is one {' or one '.join(tables)}")
    if tables:
        return BODIES[tables[0]]
    for body in BODIES.values():
        own = body("own_sections", data) if body.name != DEFAULT else []
        if own:
            raise SceneError(
                body.name,
                f"{where} has neither [{DEFAULT}] nor [{body.name}], but gives {', '.join(own)}, which only a "
                f"{body.name} scene has; add a [{body.name}] table (or a [{DEFAULT}] one and the {DEFAULT}'s fields)",
            )
    return BODIES[DEFAULT]


def of_overridden(data: dict, overridden: dict, where: str = "the scene") -> Body:
    """The body of raw scene ``data`` (:func:`of_data`, decided before any override), and a
    SceneError naming the table when the overrides (``overridden``: the data with them)
    give another body's table: a strip's field set on a sheet scene is that override's
    mistake, not a scene of both bodies."""
    from warpcloth.errors import SceneError

    body = of_data(data, where)
    foreign = [name for name in BODIES if name != body.name and name in overridden and name not in data]
    if foreign:
        raise SceneError(
            foreign[0],
            f"{where} is a {body.name} scene, and [{foreign[0]}] is a {foreign[0]} scene's table: its fields do not "
            f"apply here (the {body.name}'s own are under [{body.name}])",
        )
    return body


def of_scene(scene: object) -> Body:
    """The body a validated scene is of, or an ArgumentTypeError naming what it is."""
    for body in BODIES.values():
        if isinstance(scene, body.hook("scene_type")):
            return body
    from warpcloth.errors import ArgumentTypeError

    raise ArgumentTypeError(
        "scene", f"{scene!r} is not a scene of any body ({', '.join(BODIES)}); warpcloth.load_scene makes one"
    )


def of_scenes(scenes: list) -> Body:
    """The one body a batch of scenes is of; mixing bodies in one batch is refused."""
    found = {of_scene(s).name for s in scenes}
    if len(found) > 1:
        from warpcloth.errors import ArgumentError

        raise ArgumentError("scenes", f"a batch is of one body; these mix {' and '.join(sorted(found))} scenes")
    return named(found.pop())


def of_run(path: str | Path) -> Body:
    """The body run directory ``path`` recorded (its meta.json's ``kind``; a directory
    written before runs named their body is a strip's)."""
    meta = Path(path) / "meta.json"
    try:
        kind = json.loads(meta.read_text()).get("kind", "strip")
    except (OSError, ValueError, AttributeError):
        return BODIES["strip"]  # the strip's reader says what is wrong with the directory
    return BODIES.get(kind, BODIES["strip"])


def each(hook: str) -> dict[str, Callable[..., Any]]:
    """Hook ``hook`` of every body, by body name."""
    return {name: body.hook(hook) for name, body in BODIES.items()}
