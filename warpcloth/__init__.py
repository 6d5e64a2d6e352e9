"""warpcloth: batched Warp simulation of hanging fabric strips with hysteretic bending.

The physics follows Tagawa, Hayashi & Kijima, "Dynamic Cloth Simulation and its
Evaluation Experiments in Vacuum", as specified in MODEL.md. Typical use::

    import warpcloth
    result = warpcloth.run("damped_swing", ["damping.gamma_per_s=0.3"])
    tip_x = result.probe("tip_x", variant=0)
"""

from .analysis import crossing_times, first_period
from .control import Control
from .errors import DivergenceError, SceneError
from .model import Model
from .runner import RunResult, run, simulate
from .scene import Scene, apply_overrides, bundled_scenes, load_scene, scene_from_dict
from .solver import Solver
from .state import State
from .sweep import Sweep, expand, load_sweep
from .sweep_runner import run_sweep

__all__ = [
    "Control",
    "DivergenceError",
    "Model",
    "RunResult",
    "Scene",
    "SceneError",
    "Solver",
    "State",
    "Sweep",
    "apply_overrides",
    "bundled_scenes",
    "crossing_times",
    "expand",
    "first_period",
    "load_scene",
    "load_sweep",
    "run",
    "run_sweep",
    "scene_from_dict",
    "simulate",
]
