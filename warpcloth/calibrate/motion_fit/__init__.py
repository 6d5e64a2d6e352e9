"""Fitting free scene parameters to a measured motion with batched runs.

The paper tuned viscous damping and the rotation centre by hand until simulation matched
its vacuum experiments; this does the same by least squares. The discrepancy is the RMS
over time of simulated minus measured (the laser-line displacement, or tracked marker
positions), optionally after shifting the measured clock by a fitted start-time offset.

Search, every step one batched launch of the strip kernel:

1. **Space filling.** A seeded Latin hypercube over the bounds (``space_filling``
   variants in one batch; the sampler of a sweep's random block,
   :func:`warpcloth.scene.sampling.latin_hypercube`); the best variant starts the local
   search.
2. **Speculative Levenberg–Marquardt** (:mod:`.lm`, NumPy alone). Each iteration launches
   one batch holding the proposed step from the current Jacobian, a central-difference
   stencil around that proposal (so if it is accepted its Jacobian comes with it), and two
   more cautious steps (10× and 100× the damping) in case it is not. The start-time
   offset is a parameter too, but its Jacobian column comes from re-sampling the same
   runs, so it costs no variants. Not :func:`scipy.optimize.least_squares`: it asks for
   one residual vector (or one Jacobian) per call, each a launch of its own, where one
   launch here holds the step, its Jacobian's stencil and two fallback steps.

The uncertainty is the Gauss–Newton covariance s²(JᵀJ)⁻¹ at the optimum with s² the
residual variance. It assumes independent residuals; measured residuals are usually
correlated in time, so read it as a lower bound (the profile of the cost along each
parameter, in ``history``, shows the actual valley).

Every fit ends with a :data:`STATUSES` verdict that cannot read as success when it is
not: ``failed`` (the best run does not reproduce the measured quantity everywhere, or the
search stopped at its iteration limit), ``at_bound`` (a parameter within 0.1 % of the
range of a bound: the optimum lies beyond, the value is not an estimate),
``not_identifiable`` (two parameters correlated beyond 0.95, or a singular Jacobian: the
data do not separate them), ``poor_fit`` (RMS above :data:`~warpcloth.calibrate.noise.POOR_FIT_FACTOR` × the
measurement noise, given or estimated from the data by
:func:`~warpcloth.calibrate.noise.difference_noise`: the rule every fit shares,
:func:`~warpcloth.calibrate.noise.poor_fit_ratio`), ``mesh_dependent`` (a law without
return-point memory: its answers do not converge in h, so the values are the mesh's),
``spacing_limited`` (no continuum estimate the evidence supports, or none asked for), else
``converged``.

**The continuum limit** (:mod:`.continuum`, on by default): the best point is run at 2h
and h/2, the observed order checked against the law's, the residual extrapolated to
h → 0 by Richardson and the parameters moved to it by Gauss–Newton steps; every σ is
σ_total, with σ_noise and σ_mesh each reported, and the values at the scene's spacing kept
beside them.

The pieces: :mod:`.parameters` (the free parameters, their aliases and bounds),
:mod:`.objective` (the residuals of a batch), :mod:`.lm` (the search's algorithm),
:mod:`.search` (:func:`fit_motion`), :mod:`.continuum` (the limit h → 0), :mod:`.verdict`
(statuses, bounds, identifiability) and :mod:`.report` (:class:`FitResult`, :func:`write_fit`). Every
public name is importable from here.
"""

from .continuum import ContinuumEstimate, continuum_limit
from .lm import MAX_LAMBDA, STENCIL_STEP
from .objective import MAX_STEP_CORNERS_FREE, SHIFT, Objective, make_objective, mesh_note
from .parameters import ALIASES, HYSTERESIS_AMPLITUDES, REST_CURVATURE_SPAN, FreeParameter, free_parameters
from .report import FitResult, summarise, write_fit
from .search import MAX_SPACE_FILLING, MINIMA_FACTOR, MINIMA_SEPARATION, _other_minima, fit_motion
from .verdict import (
    AT_BOUND,
    NOT_IDENTIFIABLE_CORRELATION,
    STATUSES,
    Identifiability,
    identifiability,
    measurement_noise,
    weighted_jacobian,
)

__all__ = [
    "ALIASES",
    "AT_BOUND",
    "HYSTERESIS_AMPLITUDES",
    "MAX_LAMBDA",
    "MAX_SPACE_FILLING",
    "MAX_STEP_CORNERS_FREE",
    "MINIMA_FACTOR",
    "MINIMA_SEPARATION",
    "NOT_IDENTIFIABLE_CORRELATION",
    "REST_CURVATURE_SPAN",
    "SHIFT",
    "STATUSES",
    "STENCIL_STEP",
    "ContinuumEstimate",
    "FitResult",
    "FreeParameter",
    "Identifiability",
    "Objective",
    "fit_motion",
    "continuum_limit",
    "free_parameters",
    "identifiability",
    "measurement_noise",
    "make_objective",
    "mesh_note",
    "summarise",
    "weighted_jacobian",
    "write_fit",
]
_ = _other_minima  # importable from here for the tests of the space-filling stage
