"""Materials from Kawabata (KES-FB) measurements: read the instruments' loops, fit the
model's laws to them, compute the standard KES summary values, write a material file
(docs/model.md §13; units §1). The figure of a fit is :func:`warpcloth.viz.plots.plot_kes_fit`.

One module per concern:

- :mod:`.readers`: KES-FB1/FB2 CSV files → :class:`TensileLoop` / :class:`BendingLoop`,
  the strain unit inferred, the loops validated (§13.1);
- :mod:`.least_squares`: non-negative and inequality-constrained least squares;
- :mod:`.tensile_fit`: the tensile quartic (§13.2);
- :mod:`.bending_fit`: what every bending law's fit shares (the NNLS in D and the law's
  amplitude, the grid search in one launch, the refinement, :class:`BendingFit`);
- :mod:`.bending_tagawa2003`, :mod:`.bending_dahl`, :mod:`.bending_frictional_couple`,
  :mod:`.bending_masing`: each law's fitter (§13.3, §13.5);
- :mod:`.laws`: the registry of fitters (:data:`LAW_FITTERS`) and every law fitted to one
  loop and compared by information criterion (:func:`compare_laws`);
- :mod:`.kes_values`: EMT, WT, LT, RT, B, 2HB (§13.4);
- :mod:`.kes_fit`: both loops fitted together, with one bending law (:func:`fit_kes`);
- :mod:`.material_file`: the material file of a fit.
"""

from ..noise import POOR_FIT_FACTOR
from .bending_dahl import DAHL, EXPONENT_GRID, SCALE_K0_GRID, fit_dahl
from .bending_fit import BendingFit, LawFitter, Parameter, ShapeParameter, bending_problems, worst_status
from .bending_frictional_couple import FRICTIONAL_COUPLE, WIDTH_K0_GRID, fit_frictional_couple
from .bending_masing import MASING, fit_masing
from .bending_tagawa2003 import ALPHA_K0_GRID, TAGAWA2003, Tagawa2003Fit, fit_bending, hysteretic_offsets
from .kes_fit import KesFit, fit_kes
from .kes_values import (
    B_RANGE_PER_CM,
    G_RANGE_DEG,
    HB_CURVATURE_PER_CM,
    HB_WINDOW_PER_CM,
    HG_ANGLES_DEG,
    HG_WINDOW_DEG,
    KES_CYCLE_STEP_PER_CM,
    KES_SHEAR_STEP_DEG,
    BendingSummary,
    ShearSummary,
    TensileSummary,
    bending_summary,
    shear_summary,
    standard_cycle,
    tensile_summary,
)
from .laws import (
    AIC_TIE,
    ALL_LAWS,
    DEFAULT_LAW,
    LAW_FITTERS,
    LIKELIHOOD_RATIO_95,
    SAME_EXPONENT,
    LawComparison,
    compare_laws,
    law_fitter,
    reproduced_kes_values,
    selected_laws,
)
from .material_file import material_file_data, write_material_file
from .readers import (
    KES_FB1_GAUGE_MM,
    LOOP_CLOSURE,
    LOOP_REACH,
    MIN_BENDING_POINTS,
    MIN_LOADING_POINTS,
    PERCENT,
    SHEAR_GEOMETRIES,
    STRAIN_UNITS,
    BendingLoop,
    ShearLoop,
    TensileLoop,
    bending_loop,
    fabric_shear,
    read_bending_csv,
    read_shear_csv,
    read_tensile_csv,
    shear_loop,
    tensile_loop,
)
from .shear_fit import ShearFit, fit_shear, reproduced_shear_values
from .tensile_fit import DIVERGENCE_STRAIN, SLOPE_FLOOR, TensileFit, fit_tensile

__all__ = [
    "worst_status",
    "G_RANGE_DEG",
    "HG_ANGLES_DEG",
    "HG_WINDOW_DEG",
    "KES_SHEAR_STEP_DEG",
    "ShearSummary",
    "shear_summary",
    "ShearLoop",
    "SHEAR_GEOMETRIES",
    "fabric_shear",
    "read_shear_csv",
    "shear_loop",
    "ShearFit",
    "fit_shear",
    "reproduced_shear_values",
    "AIC_TIE",
    "ALL_LAWS",
    "ALPHA_K0_GRID",
    "B_RANGE_PER_CM",
    "BendingFit",
    "BendingLoop",
    "BendingSummary",
    "DAHL",
    "DEFAULT_LAW",
    "DIVERGENCE_STRAIN",
    "EXPONENT_GRID",
    "FRICTIONAL_COUPLE",
    "MASING",
    "HB_CURVATURE_PER_CM",
    "HB_WINDOW_PER_CM",
    "KES_CYCLE_STEP_PER_CM",
    "KES_FB1_GAUGE_MM",
    "KesFit",
    "LAW_FITTERS",
    "LIKELIHOOD_RATIO_95",
    "LOOP_CLOSURE",
    "LOOP_REACH",
    "LawComparison",
    "LawFitter",
    "MIN_BENDING_POINTS",
    "MIN_LOADING_POINTS",
    "PERCENT",
    "POOR_FIT_FACTOR",
    "Parameter",
    "SAME_EXPONENT",
    "SCALE_K0_GRID",
    "SLOPE_FLOOR",
    "STRAIN_UNITS",
    "ShapeParameter",
    "TAGAWA2003",
    "Tagawa2003Fit",
    "TensileFit",
    "TensileLoop",
    "TensileSummary",
    "WIDTH_K0_GRID",
    "bending_loop",
    "bending_problems",
    "bending_summary",
    "compare_laws",
    "fit_bending",
    "fit_dahl",
    "fit_frictional_couple",
    "fit_masing",
    "fit_kes",
    "fit_tensile",
    "hysteretic_offsets",
    "law_fitter",
    "material_file_data",
    "read_bending_csv",
    "read_tensile_csv",
    "reproduced_kes_values",
    "selected_laws",
    "standard_cycle",
    "tensile_loop",
    "tensile_summary",
    "write_material_file",
]
