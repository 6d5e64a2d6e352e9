r"""The simulation core, in SI arrays only: no scene files, no KES units, no file formats.

- :class:`StripBuilder` → :class:`Model` (what the strips *are*), ``model.state()`` →
  :class:`State` (what they *are doing*), ``model.control()`` → :class:`Control` (what
  drives them);
- a solver per integrator (:data:`SOLVERS`) advances them (what advances them);
- a :class:`Recorder` says what is recorded and when; :func:`simulate_batch` runs the
  chunked launches with progress and the divergence policy (a
  :class:`DivergenceMonitor` says which strips stopped, as typed :class:`Divergence`\ s).
"""

from warpcloth.core.divergence import DivergenceMonitor
from warpcloth.core.result import RunResult
from warpcloth.core.runner import Sink, simulate_batch
from warpcloth.core.schedule import Schedule
from warpcloth.core.solver import Solver

from .bending import law_along_path, moment_along_path, shear_force_along_path
from .builder import ClampMotion, FabricSet, Grip, StripBuilder
from .control import Control
from .divergence import Divergence
from .material import LawParameters, MaterialSI
from .model import PRECISIONS, Model
from .recorder import Recorder
from .solvers import (
    SOLVERS,
    ForwardEulerSolver,
    FusedStripSolver,
    ImexSolver,
    SemiImplicitEulerSolver,
)
from .state import State

__all__ = [
    "Divergence",
    "DivergenceMonitor",
    "PRECISIONS",
    "SOLVERS",
    "ClampMotion",
    "Control",
    "FusedStripSolver",
    "FabricSet",
    "ForwardEulerSolver",
    "Grip",
    "ImexSolver",
    "LawParameters",
    "MaterialSI",
    "Model",
    "Recorder",
    "RunResult",
    "Schedule",
    "SemiImplicitEulerSolver",
    "Sink",
    "Solver",
    "State",
    "StripBuilder",
    "law_along_path",
    "moment_along_path",
    "shear_force_along_path",
    "simulate_batch",
]
