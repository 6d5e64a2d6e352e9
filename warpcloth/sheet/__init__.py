r"""The woven sheet (stage 3 of the paper's roadmap, docs/model.md §17): a grid of mass
points along warp and weft with tension and bending per direction and shear per cell,
each with its own law from :mod:`warpcloth.kernels.laws`, batched in one launch.

- :func:`rectangle`, :func:`bias_strip` or :func:`grid_geometry` → :class:`SheetGeometry`
  (where the nodes lie and how they connect);
- :class:`SheetBuilder` with :class:`SheetMaterialSI` per sheet → :class:`SheetModel`,
  ``model.state()`` → :class:`SheetState`, ``model.control()`` → :class:`SheetControl`
  (:class:`SheetClampMotion`: rotation about any axis, translation);
- :class:`SheetSolver` advances them; :func:`simulate_sheets` (the core's one runner,
  :func:`warpcloth.core.runner.simulate_batch`, under the sheet's name) runs a
  :class:`SheetRecorder`'s schedule and returns a :class:`SheetResult` (the core's
  :class:`~warpcloth.core.result.RunResult`, with the markers in its ``tables``).
"""

from warpcloth.core.result import RunResult as SheetResult
from warpcloth.core.runner import Sink as SheetSink
from warpcloth.core.runner import simulate_batch as simulate_sheets

from .geometry import EDGE_HINGES, SheetGeometry, bias_strip, grid_geometry, rectangle
from .material import SheetMaterialSI
from .model import SheetBuilder, SheetClampMotion, SheetControl, SheetModel, SheetState
from .recorder import SheetRecorder
from .solver import SheetDivergence, SheetSolver

__all__ = [
    "EDGE_HINGES",
    "SheetBuilder",
    "SheetClampMotion",
    "SheetControl",
    "SheetDivergence",
    "SheetGeometry",
    "SheetMaterialSI",
    "SheetModel",
    "SheetRecorder",
    "SheetResult",
    "SheetSink",
    "SheetSolver",
    "SheetState",
    "bias_strip",
    "grid_geometry",
    "rectangle",
    "simulate_sheets",
]
