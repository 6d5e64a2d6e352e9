"""What every bending law's fit to a KES-FB2 loop shares (docs/model.md §13.3, §13.5).

Each law's moment is M = D K + A g(K; θ): an elastic centre line plus a hysteretic
moment that is proportional to the law's amplitude A (tagawa2003: D1, dahl: M_s,
frictional_couple: M_f) at fixed shape parameters θ (α; K_s, n; K_w), the hinge starting
fresh at the first sample. g is run along the *measured* curvature path by the kernels'
own hinge logic (:func:`warpcloth.strip.moment_along_path`) for A = 1 gf·cm/cm and D = 0, so
for each θ, (D, A) is a linear least-squares problem with D, A ≥ 0 (NNLS,
:func:`scipy.optimize.nnls`). θ is searched on a logarithmic grid (every grid point in
one kernel launch), then refined from the best grid point by SciPy's bounded Nelder–Mead
(:func:`scipy.optimize.minimize`) on ln θ inside the grid's box. A law is a
:class:`LawFitter`: its amplitude, its shape parameters and their grids; the modules
``bending_<law>.py`` each define one.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize, nnls

from warpcloth import units
from warpcloth.scene import MaterialSection, to_si
from warpcloth.strip import moment_along_path

from ..noise import difference_noise, poor_fit_ratio
from ..uncertainty import value_text
from .readers import BendingLoop

SIMPLEX_SIZE = 1e-10
"""Nelder–Mead ends when the simplex spans less than this in every ln θ (``xatol``)."""

SIMPLEX_ITERATIONS = 2000
"""…or after this many iterations."""


@dataclass(frozen=True)
class Parameter:
    """A bending-law parameter as the scene names it: [material] field (KES units), symbol, unit."""

    field: str
    symbol: str
    unit: str  # "" for a pure number


@dataclass(frozen=True)
class ShapeParameter(Parameter):
    """A shape parameter θ and its log-spaced search grid.

    The grid runs over the scaled value θ K0^(−k0_power) (``scaled`` names it, e.g. "α K0")
    from ``low`` to ``high`` in ``count`` points, so it follows the loop's size.
    """

    low: float = 1.0
    high: float = 1.0
    count: int = 1
    k0_power: int = 0
    scaled: str = ""

    def grid(self, k0: float) -> np.ndarray:
        """The grid of θ (its KES unit) for a loop whose largest ``|K|`` is ``k0`` (1/cm)."""
        scaled = np.geomspace(self.low, self.high, self.count)
        return scaled / k0**-self.k0_power if self.k0_power < 0 else scaled * k0**self.k0_power


RIGIDITY = Parameter("bending_rigidity_gf_cm2_per_cm", "D", "gf·cm²/cm")
"""The centre line's slope D, every law's first parameter."""


@dataclass(frozen=True)
class BendingFit:
    """A bending law fitted to a loop; the same shape for every law."""

    law: str  # the name in kernels/laws.py, as [material] bending_law gives it
    parameters: dict[str, float]  # [material] field (KES units) → value, in the law's order
    rms_gf_cm_per_cm: float
    rms_relative: float  # RMS / range of the measured moment
    moment: np.ndarray  # the model's moment along the measured path, gf·cm/cm
    free_parameters: int  # what the information criteria count (K0, fixed by the data, is not one)
    note: str  # e.g. a parameter at the edge of its search range; "" otherwise
    sigma: dict[str, float] = field(default_factory=dict)  # standard uncertainty of each free parameter

    @property
    def rigidity_gf_cm2_per_cm(self) -> float:
        """D, the slope of the centre line M = D K."""
        return self.parameters[RIGIDITY.field]

    @property
    def points(self) -> int:
        """The number of samples fitted (n of the information criteria)."""
        return len(self.moment)

    def _log_likelihood_term(self) -> float:
        # n ln(SSE / n), SSE = n RMS² (an exact fit would be −∞: floored)
        return self.points * math.log(max(self.rms_gf_cm_per_cm**2, 1e-300))

    def aic(self) -> float:
        """Akaike's criterion n ln(SSE/n) + 2k (Gaussian residuals of one unknown variance)."""
        return self._log_likelihood_term() + 2 * self.free_parameters

    def bic(self) -> float:
        """The Bayesian (Schwarz) criterion n ln(SSE/n) + k ln n."""
        return self._log_likelihood_term() + self.free_parameters * math.log(self.points)

    def material_section(self) -> MaterialSection:
        """A [material] with the fitted law and its parameters (every other field the default)."""
        return MaterialSection(bending_law=self.law, **self.parameters)


def poor_fit(what: str, rms: float, unit: str, samples: np.ndarray) -> str | None:
    """Why a fit whose RMS is above :data:`~warpcloth.calibrate.noise.POOR_FIT_FACTOR` × the
    noise of its data (from their 4th differences; the rule of every fit,
    :func:`~warpcloth.calibrate.noise.poor_fit_ratio`) is not a fit; None when it is not that far."""
    noise = difference_noise([samples])
    ratio = poor_fit_ratio(rms, noise)
    if ratio is not None:
        return (
            f"the {what} RMS {rms:.4g} {unit} is {ratio:.1f}× the noise of the data ({noise:.3g} {unit}, "
            "from its 4th differences): the model does not describe this loop"
        )
    return None


def worst_status(*statuses: str) -> str:
    """The least trusted of several fits' statuses (:data:`STATUS_ORDER`, then ``converged``)."""
    return min(statuses, key=lambda s: STATUS_ORDER.index(s) if s in STATUS_ORDER else len(STATUS_ORDER))


AIC_TIE = 2.0
"""A ΔAIC below this is no preference between two models of a loop."""

STATUS_ORDER = ("failed", "poor_fit", "not_identifiable", "at_bound")
"""A KES fit's status is the first of these any of its problems has (else ``converged``): the
cause before its symptoms (a loop without hysteresis sends the shape parameters to bounds)."""


def elastic_aic(loop: BendingLoop) -> float:
    """AIC of the elastic line M = D K (one parameter) on the loop: the baseline a
    hysteretic law must beat for its hysteresis to be told by the data."""
    k, m = loop.curvature, loop.moment
    d = max(0.0, float(np.dot(k, m) / np.dot(k, k)))
    sse = float(np.sum((d * k - m) ** 2))
    return len(k) * math.log(max(sse / len(k), 1e-300)) + 2


def bending_problems(
    fit: BendingFit, loop: BendingLoop, what: str = "bending", unit: str = "gf·cm/cm", line: str = "M = D K"
) -> list[tuple[str, str]]:
    """(status, why) of each reason a bending fit is not trusted, in :data:`STATUS_ORDER`:
    ``failed`` (a value not finite), ``poor_fit`` (the law does not describe the loop),
    ``not_identifiable`` (the elastic line fits the loop as well: no hysteresis for the
    law's parameters to describe, which also sends them to the edges of their search),
    ``at_bound`` (a parameter at the edge of its search). ``what``, ``unit`` and ``line``
    word it for a law fitted to another loop (shear: ``Fs = G φ``, gf/cm)."""
    found = []
    if not all(math.isfinite(float(v)) for v in [*fit.parameters.values(), fit.rms_gf_cm_per_cm]):
        found.append(("failed", f"a fitted {fit.law} value is not finite"))
    gain = elastic_aic(loop) - fit.aic()
    if gain < AIC_TIE:
        found.append(
            (
                "not_identifiable",
                f"the loop shows no hysteresis the {fit.law} law can tell: the elastic line "
                f"{line} fits it as well (AIC better by {gain:.1f} < {AIC_TIE:g} for "
                f"{fit.free_parameters - 1} more parameters), so its hysteresis parameters are not determined "
                "by these data",
            )
        )
    if "edge of its search range" in fit.note:
        found.append(("at_bound", fit.note))
    why = poor_fit(what, fit.rms_gf_cm_per_cm, unit, loop.moment)
    if why is not None:
        found.append(("poor_fit", why))
    return sorted(found, key=lambda problem: STATUS_ORDER.index(problem[0]))


def _linear_part(curvature: np.ndarray, moment: np.ndarray, offset: np.ndarray) -> tuple[float, float, float]:
    # D, A ≥ 0 of M = D K + A g for one shape, and the sum of squared residuals.
    (d, a), _ = nnls(np.column_stack([curvature, offset]), moment)
    return float(d), float(a), float(np.sum((d * curvature + a * offset - moment) ** 2))


@dataclass(frozen=True)
class LawFitter:
    """How one bending law is fitted: its amplitude A, its shape parameters θ (with their
    grids) and, for tagawa2003, the parameter the data fix (K0 = the loop's largest ``|K|``)."""

    law: str
    amplitude: Parameter
    shape: tuple[ShapeParameter, ...]
    k0: Parameter | None = None
    result: type[BendingFit] = BendingFit

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """Every parameter of the law, in the order fits report them."""
        return (RIGIDITY, self.amplitude, *self.shape, *((self.k0,) if self.k0 else ()))

    @property
    def free_parameters(self) -> int:
        """D, A and the shape parameters (K0 comes from the data)."""
        return 2 + len(self.shape)

    def describe(self, fit: BendingFit, digits: int = 6) -> str:
        """The fit's parameters as text with their units and standard uncertainties, e.g.
        ``D 0.1 ± 0.0003 gf·cm²/cm, …`` (K0, which the data fix, is marked so:
        :func:`~warpcloth.calibrate.uncertainty.value_text`)."""

        return ", ".join(
            value_text(p.symbol, fit.parameters[p.field], fit.sigma.get(p.field), p.unit, digits)
            for p in self.parameters
        )

    def uncertainties(
        self, loop: BendingLoop, d: float, a: float, shape: np.ndarray, sse: float, device: str | None = "cpu"
    ) -> dict[str, float]:
        """Standard uncertainties of D, A and the shape parameters at the optimum, from the
        linearised model: cov = s² (JᵀJ)⁻¹, s² = SSE / (n − k), J = ∂M/∂(D, A, θ) with the
        θ columns by central differences (one launch); NaN where the amplitude is 0 (the
        shape parameters then have no effect) or the Jacobian is singular."""
        k, k0 = loop.curvature, loop.k0
        step = 1e-4
        probes = np.concatenate(
            [shape[None, :] * np.exp(step * np.eye(len(shape))), shape[None, :] * np.exp(-step * np.eye(len(shape)))]
        )
        offsets = self.unit_offsets(k, np.vstack([shape[None, :], probes]), k0, device)
        columns = [k, offsets[:, 0]]
        n_shape = len(shape)
        for j in range(n_shape):
            # ∂M/∂θ_j = A ∂g/∂ln θ_j / θ_j
            columns.append(a * (offsets[:, 1 + j] - offsets[:, 1 + n_shape + j]) / (2 * step * shape[j]))
        jacobian = np.column_stack(columns)
        names = [RIGIDITY.field, self.amplitude.field, *(p.field for p in self.shape)]
        dof = len(k) - len(names)
        if a == 0.0 or dof <= 0:
            return {name: math.nan for name in names}
        try:
            covariance = sse / dof * np.linalg.inv(jacobian.T @ jacobian)
        except np.linalg.LinAlgError:
            return {name: math.nan for name in names}
        return {
            name: float(math.sqrt(v)) if v >= 0 else math.nan
            for name, v in zip(names, np.diag(covariance), strict=True)
        }

    def _fixed(self, k0: float) -> dict[str, float]:
        return {self.k0.field: k0} if self.k0 else {}

    def unit_offsets(
        self, curvature_per_cm: np.ndarray, shapes: np.ndarray, k0_per_cm: float, device: str | None = "cpu"
    ) -> np.ndarray:
        """Hysteretic moment g(θ; path) per gf·cm/cm of the amplitude along a curvature
        path (1/cm), one column per row of ``shapes`` (``[point, shape parameter]``, KES
        units), all in one kernel launch with D = 0; the hinge starts fresh at the path's
        first sample. Returns ``[sample, point]``."""
        fixed = self._fixed(k0_per_cm)
        materials = [
            to_si(
                MaterialSection(
                    bending_law=self.law,
                    bending_rigidity_gf_cm2_per_cm=0.0,
                    **{self.amplitude.field: 1.0},
                    **fixed,
                    **{p.field: float(v) for p, v in zip(self.shape, row, strict=True)},
                )
            )
            for row in np.atleast_2d(shapes)
        ]
        k = np.asarray(curvature_per_cm, dtype=np.float64) * units.CURVATURE_PER_CM
        moment, _ = moment_along_path(materials, k[:, None], device=device)
        return moment / units.MOMENT_GF_CM_PER_CM

    def fit(self, loop: BendingLoop, device: str | None = "cpu") -> BendingFit:
        """Fit D, A and θ to the whole loop (see the module docstring)."""
        k, m, k0 = loop.curvature, loop.moment, loop.k0
        grids = [p.grid(k0) for p in self.shape]
        points = np.array(list(itertools.product(*grids)))
        offsets = self.unit_offsets(k, points, k0, device)
        sse = np.array([_linear_part(k, m, offsets[:, i])[2] for i in range(len(points))])
        best = int(np.argmin(sse))
        index = np.unravel_index(best, [p.count for p in self.shape])
        logs = [np.log(g) for g in grids]

        def objective(log_shape: np.ndarray) -> float:
            return _linear_part(k, m, self.unit_offsets(k, np.exp(log_shape)[None, :], k0, device)[:, 0])[2]

        # Nelder–Mead on ln θ inside the grid's box from the best grid point, the first
        # simplex one grid step along each ln θ, inwards from an edge (SciPy clips a
        # vertex onto the box, which would flatten a simplex started outwards).
        steps = np.array([(lg[1] - lg[0]) * (-1 if i == len(lg) - 1 else 1) for lg, i in zip(logs, index, strict=True)])
        start = np.log(points[best])
        search = minimize(
            objective,
            start,
            method="Nelder-Mead",
            bounds=[(lg[0], lg[-1]) for lg in logs],
            options={
                "initial_simplex": np.vstack([start, start + np.diag(steps)]),
                "xatol": SIMPLEX_SIZE,
                "fatol": np.inf,
                "maxiter": SIMPLEX_ITERATIONS,
            },
        )
        x, refined = search.x, float(search.fun)
        shape = np.exp(x)
        if sse[best] < refined:  # a flat objective (no hysteresis): keep the grid's point
            shape = points[best]
        edges = [
            (p, v)
            for p, i, v, lg in zip(self.shape, index, shape, logs, strict=True)
            if i in (0, p.count - 1) or min(abs(math.log(v) - lg[0]), abs(math.log(v) - lg[-1])) < SIMPLEX_SIZE
        ]
        note = ""
        if edges:
            note = (
                "; ".join(
                    f"{p.symbol} at the edge of its search range ({p.scaled} = {v / k0**p.k0_power:g})"
                    for p, v in edges
                )
                + "; the loop may not have the model's shape"
            )
        offset = self.unit_offsets(k, shape[None, :], k0, device)[:, 0]
        d_fit, a_fit, total = _linear_part(k, m, offset)
        if a_fit == 0.0:
            symbols = [p.symbol for p in self.shape]
            note = (
                f"the loop shows no hysteresis ({self.amplitude.symbol} = 0): {', '.join(symbols)} "
                f"{'has' if len(symbols) == 1 else 'have'} no effect"
            )
        rms = math.sqrt(total / len(k))
        parameters = {
            RIGIDITY.field: d_fit,
            self.amplitude.field: a_fit,
            **{p.field: float(v) for p, v in zip(self.shape, shape, strict=True)},
            **self._fixed(k0),
        }
        sigma = self.uncertainties(loop, d_fit, a_fit, shape, total, device)
        return self.result(
            self.law,
            parameters,
            rms,
            rms / (float(np.ptp(m)) or 1.0),
            d_fit * k + a_fit * offset,
            self.free_parameters,
            note,
            sigma,
        )
