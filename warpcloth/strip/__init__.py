r"""The strip, one of the two bodies on the core (:mod:`warpcloth.core`), in SI arrays
only: no scene files, no KES units, no file formats.

- :class:`StripBuilder` → :class:`StripModel` (what the strips *are*), ``model.state()`` →
  :class:`StripState` (what they *are doing*), ``model.control()`` → :class:`StripControl`
  (what drives them); ``Model``, ``State`` and ``Control`` are their former names;
- a solver per integrator (:data:`SOLVERS`) advances them (what advances them);
- a :class:`Recorder` says what is recorded and when; :func:`simulate_batch` (the core's
  one runner) runs the chunked launches with progress and the divergence policy (a
  :class:`DivergenceMonitor` says which strips stopped, as typed :class:`Divergence`\ s).
"""

from warpcloth.core.divergence import DivergenceMonitor
from warpcloth.core.result import RunResult
from warpcloth.core.runner import Sink, simulate_batch
from warpcloth.core.schedule import Schedule
from warpcloth.core.solver import Solver

from .bending import law_along_path, moment_along_path, shear_force_along_path
from .builder import ClampMotion, FabricSet, Grip, StripBuilder
from .control import StripControl
from .divergence import Divergence
from .material import LawParameters, MaterialSI
from .model import PRECISIONS, StripModel
from .recorder import Recorder
from .solvers import (
    SOLVERS,
    ForwardEulerSolver,
    FusedStripSolver,
    ImexSolver,
    SemiImplicitEulerSolver,
    TrapezoidalImexSolver,
)
from .state import StripState

Model, State, Control = StripModel, StripState, StripControl  # the former names, kept working

__all__ = [
    "Divergence",
    "DivergenceMonitor",
    "PRECISIONS",
    "SOLVERS",
    "ClampMotion",
    "Control",
    "StripControl",
    "StripModel",
    "StripState",
    "FusedStripSolver",
    "FabricSet",
    "ForwardEulerSolver",
    "Grip",
    "ImexSolver",
    "TrapezoidalImexSolver",
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
