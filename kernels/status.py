"""Health codes a strip's thread writes to ``status`` when it stops (docs/model.md §11)."""

STATUS_OK = 0
STATUS_STRAIN = 1
STATUS_FOLDED = 2
STATUS_NONFINITE_ENERGY = 3
STATUS_BUDGET = 4  # set by the runner, not a kernel: the energy budget no longer closes (warpcloth/strip/runner.py)
STATUS_CELL_COLLAPSED = 5  # a sheet's cell sheared flat: warp and weft (nearly) parallel
