"""Materials from Kawabata (KES-FB) measurements: read the instruments' loops, fit the
model's laws to them, compute the standard KES summary values, write a material file
(docs/model.md §13; units §1). The figure of a fit is :func:`warpcloth.viz.plots.plot_kes_fit`.

One module per concern:

- :mod:`.readers`: KES-FB1/FB2 CSV files → :class:`TensileLoop` / :class:`BendingLoop`,
  the strain unit inferred, the loops validated (§13.1);
- :mod:`.least_squares`: non-negative and inequality-constrained least squares;
- :mod:`.tensile_fit`: the tensile quartic (§13.2);
- :mod:`.bending_tagawa2003`: the paper's bending law (§4) fitted to a loop (§13.3);
  another bending law would be one more module beside it;
- :mod:`.kes_values`: EMT, WT, LT, RT, B, 2HB (§13.4);
- :mod:`.kes_fit`: both loops fitted together (:func:`fit_kes`);
- :mod:`.material_file`: the material file of a fit.
"""

from .bending_tagawa2003 import ALPHA_K0_GRID, BendingFit, fit_bending, hysteretic_offsets
from .kes_fit import KesFit, fit_kes
from .kes_values import (
    B_RANGE_PER_CM,
    HB_CURVATURE_PER_CM,
    HB_WINDOW_PER_CM,
    BendingSummary,
    TensileSummary,
    bending_summary,
    tensile_summary,
)
from .material_file import material_file_data, write_material_file
from .readers import (
    KES_FB1_GAUGE_MM,
    LOOP_CLOSURE,
    LOOP_REACH,
    MIN_BENDING_POINTS,
    MIN_LOADING_POINTS,
    PERCENT,
    STRAIN_UNITS,
    BendingLoop,
    TensileLoop,
    bending_loop,
    read_bending_csv,
    read_tensile_csv,
    tensile_loop,
)
from .tensile_fit import DIVERGENCE_STRAIN, SLOPE_FLOOR, TensileFit, fit_tensile

__all__ = [
    "ALPHA_K0_GRID",
    "B_RANGE_PER_CM",
    "DIVERGENCE_STRAIN",
    "HB_CURVATURE_PER_CM",
    "HB_WINDOW_PER_CM",
    "KES_FB1_GAUGE_MM",
    "LOOP_CLOSURE",
    "LOOP_REACH",
    "MIN_BENDING_POINTS",
    "MIN_LOADING_POINTS",
    "PERCENT",
    "SLOPE_FLOOR",
    "STRAIN_UNITS",
    "BendingFit",
    "BendingLoop",
    "BendingSummary",
    "KesFit",
    "TensileFit",
    "TensileLoop",
    "TensileSummary",
    "bending_loop",
    "bending_summary",
    "fit_bending",
    "fit_kes",
    "fit_tensile",
    "hysteretic_offsets",
    "material_file_data",
    "read_bending_csv",
    "read_tensile_csv",
    "tensile_loop",
    "tensile_summary",
    "write_material_file",
]
