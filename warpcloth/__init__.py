"""warpcloth: batched Warp simulation of hanging fabric strips with hysteretic bending.

The physics follows Tagawa, Hayashi & Kijima, "Dynamic Cloth Simulation and its
Evaluation Experiments in Vacuum", as written up in docs/model.md. Typical use::

    import warpcloth as wc
    result = wc.run("damped_swing", ["damping.gamma_per_s=0.3"])
    tip_x = result.probe("tip_x", variant=0)

The namespaces :mod:`warpcloth.core` (what every body shares), :mod:`warpcloth.strip` and
:mod:`warpcloth.sheet` (the two bodies, in SI), :mod:`warpcloth.bodies` (their registry),
:mod:`warpcloth.scene`, :mod:`warpcloth.calibrate`, :mod:`warpcloth.viz` and
:mod:`warpcloth.io` hold the rest; ``result = wc.run("shear_swing")`` runs a sheet as
``wc.run("damped_swing")`` runs a strip.

The names below are imported when first used (PEP 562), so ``import warpcloth.cli``
costs no Warp, NumPy or pandas start: the command installs its Ctrl-C handling before
those heavy imports, and an interrupt while they load exits 130 with one line.
"""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path

from .errors import (
    ArgumentError,
    ArgumentTypeError,
    DataFileError,
    DivergenceError,
    InternalError,
    OptionError,
    PlausibilityWarning,
    ResourceError,
    SceneError,
    WarpclothError,
)


def _beside_the_source() -> None:
    # In a clone's root, where a researcher opens Jupyter, `import warpcloth` finds this
    # folder rather than the installed package, and kernels/ and scenes/ (installed inside
    # warpcloth, see pyproject.toml) sit beside it: the package's path reaches them there.
    here = Path(__file__).resolve().parent
    if not (here / "kernels").is_dir() and (here.parent / "kernels" / "__init__.py").is_file():
        __path__.append(str(here.parent))


_beside_the_source()

_SUBMODULES = ("bodies", "calibrate", "core", "io", "scene", "sheet", "sim", "strip", "viz")
_LAZY = {
    "load_recording": "io.load",
    "Recording": "io.recording",
    "first_period": "metrics",
    "run": "runs",
    "simulate": "runs",
    "Scene": "scene",
    "Sweep": "scene",
    "bundled_scenes": "scene",
    "expand": "scene",
    "load_scene": "scene",
    "load_sweep": "scene",
    "scene_from_dict": "scene",
    "RunResult": "core.result",
    "run_sweep": "sweeps",
    "export_usd": "viz.usd",
}
"""Public name → the module (below warpcloth) that defines it."""


def __getattr__(name: str) -> object:
    """Import a public name's module on first use (see the module docstring)."""
    if name in _SUBMODULES or (not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}")):
        return importlib.import_module(f".{name}", __name__)  # wc.metrics and every other submodule
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'warpcloth' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public names, imported or not."""
    return sorted(set(globals()) | set(__all__))


__all__ = [
    "ArgumentError",
    "ArgumentTypeError",
    "DataFileError",
    "DivergenceError",
    "InternalError",
    "OptionError",
    "PlausibilityWarning",
    "ResourceError",
    "Recording",
    "RunResult",
    "Scene",
    "SceneError",
    "Sweep",
    "WarpclothError",
    "bundled_scenes",
    "calibrate",
    "expand",
    "export_usd",
    "first_period",
    "io",
    "load_recording",
    "load_scene",
    "load_sweep",
    "run",
    "run_sweep",
    "scene",
    "scene_from_dict",
    "sim",
    "simulate",
    "strip",
    "sheet",
    "core",
    "bodies",
    "viz",
]
