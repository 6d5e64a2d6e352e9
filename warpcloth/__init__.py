"""warpcloth: batched Warp simulation of hanging fabric strips with hysteretic bending.

The physics follows Tagawa, Hayashi & Kijima, "Dynamic Cloth Simulation and its
Evaluation Experiments in Vacuum", as written up in docs/model.md. Typical use::

    import warpcloth as wc
    result = wc.run("damped_swing", ["damping.gamma_per_s=0.3"])
    tip_x = result.probe("tip_x", variant=0)

The namespaces :mod:`warpcloth.sim` (the SI simulation core), :mod:`warpcloth.scene`,
:mod:`warpcloth.calibrate`, :mod:`warpcloth.viz` and :mod:`warpcloth.io` hold the rest.
"""

from . import calibrate, io, scene, sim, viz
from .errors import DataFileError, DivergenceError, OptionError, ResourceError, SceneError, WarpclothError
from .io.load import load_recording
from .io.recording import Recording
from .metrics import first_period
from .runs import run, simulate
from .scene import Scene, Sweep, bundled_scenes, expand, load_scene, load_sweep, scene_from_dict
from .sim import RunResult
from .sweeps import run_sweep
from .viz.usd import export_usd

__all__ = [
    "DataFileError",
    "DivergenceError",
    "OptionError",
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
    "viz",
]
