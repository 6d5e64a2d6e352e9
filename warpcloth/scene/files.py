"""Scene files: by path or bundled name, parsed, overridden and validated."""

from __future__ import annotations

import importlib.resources
from pathlib import Path
from typing import Any

from warpcloth import bodies
from warpcloth.errors import ArgumentError, DataFileError, SceneError, checked_path

from .locate import located
from .materials import MATERIAL_FILE_KEY, with_material_file
from .overrides import Overrides, apply_overrides
from .parse import parse_section, parse_toml, read_toml_text
from .schema import Scene
from .step import AUTO, with_chosen_step
from .validate import validate_scene


def bundled_scenes() -> list[str]:
    """Names of the scenes shipped with warpcloth."""
    root = importlib.resources.files("warpcloth.scenes")
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def _rebase_material_file(data: dict, directory: Path) -> None:
    # A material path written in a scene file, in [material] or among the values of a
    # [sweep], is relative to that file, not to the directory the command runs in.
    def rebase(ref: Any) -> Any:
        if isinstance(ref, str) and ref.endswith(".toml") and not Path(ref).is_absolute():
            return str((directory / ref).resolve())
        return ref

    material = data.get("material")
    if isinstance(material, dict) and "from_file" in material:
        material["from_file"] = rebase(material["from_file"])
    sweep = data.get("sweep")
    for block in ("grid", "zip"):
        table = sweep.get(block) if isinstance(sweep, dict) else None
        if isinstance(table, dict) and isinstance(table.get(MATERIAL_FILE_KEY), list):
            table[MATERIAL_FILE_KEY] = [rebase(ref) for ref in table[MATERIAL_FILE_KEY]]


def is_path(name_or_path: str | Path) -> bool:
    """Whether a scene or material reference is a file path: it has a directory part or
    ends in ``.toml``. Anything else is a bare name, looked up among the bundled files."""
    path = Path(name_or_path)
    # the raw text too: Path("./damped_swing") normalises its "./" away
    written = str(name_or_path)
    return path.suffix == ".toml" or len(path.parts) > 1 or path.is_absolute() or "/" in written or "\\" in written


def scene_source(name_or_path: str | Path) -> tuple[str, str]:
    """The TOML text of a scene given by path or by bundled name, and how to name it in a
    message (the path, or ``bundled scene NAME``).

    A path (see :func:`is_path`) must name an existing file: it never falls back on the
    bundled scene of the same stem.
    """
    path = Path(checked_path("name_or_path", name_or_path))
    if is_path(name_or_path):
        if not path.is_file():
            why = (
                "is a directory"
                if path.is_dir()
                else "ends in .toml"
                if path.suffix == ".toml"
                else "has a directory part"
            )
            raise DataFileError(
                str(name_or_path),
                f"no such scene file (a path, because it {why}; a bundled "
                f"scene is named without either: {', '.join(bundled_scenes())})",
            )
        return read_toml_text(path), str(path)
    resource = importlib.resources.files("warpcloth.scenes") / f"{path.name}.toml"
    if not resource.is_file():
        raise ArgumentError(
            "name_or_path",
            f"no bundled scene {str(name_or_path)!r} (bundled: "
            f"{', '.join(bundled_scenes())}; a scene file is a path ending in .toml)",
        )
    return resource.read_text(), f"bundled scene {path.name}"


def _read_scene(name_or_path: str | Path) -> tuple[dict, str, str]:
    text, where = scene_source(name_or_path)
    data = parse_toml(text, where, "scene")
    if is_path(name_or_path):
        _rebase_material_file(data, Path(name_or_path).parent)
    return data, text, where


def read_scene_file(name_or_path: str | Path) -> dict:
    """Raw TOML data of a scene given by path or by bundled name (``damped_swing``), see
    :func:`scene_source`. A relative ``material.from_file`` path in the file is made
    absolute against the scene file's directory.
    """
    return _read_scene(name_or_path)[0]


def strip_sections(data: dict) -> list[str]:
    """The sections only a strip has: none that a file without [strip] could give (a
    scene without a body's table is a strip with the default geometry)."""
    return []


def strip_scene_from_dict(data: dict, choose_step: bool = True) -> Scene:
    """Parse and validate raw strip-scene data.

    A ``material.from_file`` (path or bundled name) fills every [material] field the data
    do not set; the scene holds the explicit values afterwards, so ``to_dict()`` re-reads
    to the same scene. ``integrator.dt_s = "auto"`` is replaced by the step
    :func:`~warpcloth.scene.step.with_chosen_step` picks for this scene alone, unless
    ``choose_step`` is false (a sweep picks one step for all its variants).
    """
    if isinstance(data, dict) and "sheet" in data:
        raise SceneError("sheet", "this is a sheet scene (warpcloth.scene_from_dict reads either body's)")
    scene = parse_section(Scene, with_material_file(data), "")
    validate_scene(scene)
    if choose_step and scene.integrator.dt_s == AUTO:
        (scene,) = with_chosen_step([scene])
    return scene


def scene_from_dict(data: dict) -> Any:
    """Parse and validate raw scene data of either body (a strip's :class:`Scene`, a sheet's
    :class:`~warpcloth.scene.sheet.SheetScene`, by the table it has: :func:`warpcloth.bodies.of_data`).
    ``integrator.dt_s = "auto"`` of a strip is replaced by the step chosen for it alone."""
    if not isinstance(data, dict):
        raise SceneError("scene", f"expected a table of scene sections, got {type(data).__name__}")
    return bodies.of_data(data)("scene_from_dict", data)


def load_scene(name_or_path: str | Path, overrides: Overrides = ()) -> Any:
    """Read a scene of either body by path or bundled name, apply overrides (``"key=value"``
    strings as ``--set`` takes them, or a dict ``{"damping.gamma_per_s": 0.5}``), validate
    it and check it can run (its step within the stability bound); every error names the
    field and where it was set.

    A ``[sweep]`` section is ignored here: this is the sweep's base scene.
    """
    data, text, where = _read_scene(name_or_path)
    data.pop("sweep", None)
    try:
        overridden = apply_overrides(data, overrides)
        body = bodies.of_overridden(data, overridden, where)
        scene = body("check_scene", body("scene_from_dict", overridden))
    except SceneError as exc:
        raise located(exc, text, where, overrides) from None
    return scene
