"""Materials from Kawabata (KES-FB) measurements: read the instruments' loops, fit the
model's laws to them, compute the standard KES summary values, write a material file.

**Tensile (KES-FB1)**, a CSV of strain (or extension) and force per width T in gf/cm, in
the order measured: loading from the first row to the maximum strain, then (optionally)
unloading. The unit of the first column comes from its header when the header says
(``strain_percent``, ``strain_%``, ``strain_fraction``, ``extension_mm``; a plain
``strain`` does not say), else from ``strain_unit`` (``percent``, ``fraction`` or
``mm``), else automatically: a column whose maximum exceeds 1 is in percent, otherwise a
fraction (a fabric is never stretched by 100 %, nor loaded to its 500 gf/cm standard
load below 1 % strain). Extension in mm is divided by the gauge length
(``gauge_length_mm``, KES-FB1 standard 50 mm). The quartic
T(ε) = a1 ε + a2 ε² + a3 ε³ + a4 ε⁴ (ε a fraction, no constant term) is the least-squares
fit to the loading branch; when it would not increase on [0, max(ε_max, divergence
strain)], as a scene requires, the fit is constrained to dT/dε ≥ 10⁻³ Fm/εm there instead
(and says so).

**Bending (KES-FB2)**, a CSV of curvature K in 1/cm and moment per width M in
gf·cm/cm: one cycle from rest, e.g. the standard 0 → +2.5 → −2.5 → 0 1/cm. The model
M = D K + h (the hinge starts fresh at the first sample: rising branch, no offset) is
run along the measured curvature path by the kernel's own hinge logic. K0 is the
loop's largest |K|. For a fixed α the hysteretic offset is proportional to D1 (the
branch functions are, and the loop centre after a reversal depends on the offset only
through (M0 ∓ H)/D1), so M = D K + D1 h₁(α; path) with h₁ the offset for D1 = 1 gf·cm/cm:
for each α, (D, D1) is a linear least-squares problem (with D, D1 ≥ 0). α is searched on
a logarithmic grid of α K0 in [0.05, 60] (all in one kernel launch), then refined by
golden-section search between the best grid point's neighbours.

**KES summary values** (computed from the data, not from the fit):

- EMT (%): the strain where loading ends (the maximum strain; KES-FB1 reverses at the
  preset maximum load Fm, 500 gf/cm as standard); Fm is the force there.
- WT (gf·cm/cm²): tensile energy ∫ T dε along the loading branch (ε a fraction; trapezoids).
- LT: linearity WT / (½ Fm εm) (1 for a straight line).
- RT (%): resilience, 100 × (∫ T dε along the unloading branch) / WT; only with unloading data.
- B (gf·cm²/cm): mean of the least-squares slopes dM/dK for 0.5 ≤ |K| ≤ 1.5 1/cm on both
  branches (rising and falling K) on both sides (K > 0 and K < 0).
- 2HB (gf·cm/cm): mean over K = +1 and K = −1 1/cm of the hysteresis width
  M(rising) − M(falling), each read off a straight line through the branch's points
  within ±0.1 1/cm (linear interpolation where fewer than 3 points lie there).

Residuals are RMS(fit − data) in KES units and that RMS relative to the data's range.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tomli_w

from warpcloth import units
from warpcloth.errors import SceneError
from warpcloth.io.atomic import write_text_atomically
from warpcloth.io.measured import bundled_data, read_text
from warpcloth.scene import (
    IntegratorSection,
    MaterialSection,
    material_fields,
    tensile_slope_minimum,
    validate_material,
)
from warpcloth.sim import MaterialSI, moment_along_path

PERCENT = units.STRAIN_PERCENT

KES_FB1_GAUGE_MM = 50.0
"""Standard KES-FB1 gauge length (sample length between the chucks)."""

DIVERGENCE_STRAIN = IntegratorSection().divergence_strain
"""Strain up to which a fitted T(ε) must increase (the scene default)."""

MIN_LOADING_POINTS = 6
"""The quartic has 4 coefficients; 2 more points leave a residual to judge it by."""

MIN_BENDING_POINTS = 12
"""At least 3 parameters on 3 legs (0 → +K0, +K0 → −K0, −K0 → 0) of a few points each."""

LOOP_CLOSURE = 0.1
"""A loop closes if it ends within this fraction of its largest |K| of its start."""

LOOP_REACH = 0.5
"""Each sign of curvature must reach this fraction of the loop's largest |K|."""

SLOPE_FLOOR = 1e-3
"""Constrained tensile fit: dT/dε ≥ SLOPE_FLOOR × Fm / εm (so T strictly increases)."""

ALPHA_K0_GRID = (0.05, 60.0, 64)
"""Coarse α search: α K0 from nearly linear branches to a step, log-spaced, n points."""

B_RANGE_PER_CM = (0.5, 1.5)
"""KES B: the |K| range (1/cm) of the slopes that are averaged."""

HB_CURVATURE_PER_CM = 1.0
"""KES 2HB: the hysteresis width is read at K = ± this (1/cm)."""

HB_WINDOW_PER_CM = 0.1
"""2HB: a branch's moment at ±1 1/cm is a line through its points within ± this (1/cm)."""

_TENSILE_NAMES = ({"strain", "extension", "elongation", "eps", "epsilon"}, {"force", "load", "tension", "t", "f"})
_BENDING_NAMES = ({"curvature", "k", "kappa"}, {"moment", "bending", "m"})
_STRAIN_UNITS = ("percent", "fraction", "mm")


@dataclass(frozen=True)
class TensileLoop:
    """A KES-FB1 tensile loop in measurement order: strain (fraction), force per width (gf/cm)."""

    strain: np.ndarray
    force: np.ndarray
    rows: np.ndarray  # where each point came from: file line (1-based) or sample number
    source: str  # file name, or "tensile data"
    row_label: str = "line"
    strain_unit: str = "fraction"  # how the first column was read, and why

    @property
    def turn(self) -> int:
        """Index of the maximum strain: loading is [0, turn], unloading [turn, end]."""
        return int(np.argmax(self.strain))

    @property
    def loading(self) -> slice:
        """The loading (upper) branch."""
        return slice(0, self.turn + 1)

    @property
    def unloading(self) -> slice:
        """The unloading branch (starts at the turn; a single point when there is none)."""
        return slice(self.turn, len(self.strain))


@dataclass(frozen=True)
class BendingLoop:
    """A KES-FB2 bending loop in measurement order: curvature (1/cm), moment per width (gf·cm/cm)."""

    curvature: np.ndarray
    moment: np.ndarray
    rows: np.ndarray
    source: str
    row_label: str = "line"

    @property
    def k0(self) -> float:
        """The loop's largest |K| (1/cm), where the model's loop closes."""
        return float(np.max(np.abs(self.curvature)))

    def legs(self) -> list[slice]:
        """The cycle's legs: split at its first maximum and first minimum of K."""
        cuts = sorted({0, int(np.argmax(self.curvature)), int(np.argmin(self.curvature)), len(self.curvature) - 1})
        return [slice(a, b + 1) for a, b in zip(cuts[:-1], cuts[1:], strict=False)]


@dataclass(frozen=True)
class TensileFit:
    """The quartic T(ε) fitted to the loading branch."""

    coefficients: list[float]  # a1..a4, gf/cm (ε a fraction)
    rms_gf_per_cm: float
    rms_relative: float  # RMS / range of the loading branch's force
    constrained: bool
    note: str  # why the fit was constrained; "" when it was not

    def __call__(self, strain: np.ndarray) -> np.ndarray:
        """T(ε) in gf/cm."""
        a1, a2, a3, a4 = self.coefficients
        e = np.asarray(strain, dtype=np.float64)
        return e * (a1 + e * (a2 + e * (a3 + e * a4)))


@dataclass(frozen=True)
class BendingFit:
    """D, D1, α (K0 from the data) of the hysteretic bending law, and the fitted path."""

    rigidity_gf_cm2_per_cm: float  # D
    d1_gf_cm_per_cm: float
    alpha_cm: float
    k0_per_cm: float
    rms_gf_cm_per_cm: float
    rms_relative: float  # RMS / range of the measured moment
    moment: np.ndarray  # the model's moment along the measured path, gf·cm/cm
    note: str  # e.g. α at the edge of its search range; "" otherwise


@dataclass(frozen=True)
class TensileSummary:
    """KES-FB1 values of a loop (definitions in the module docstring)."""

    emt_percent: float
    fm_gf_per_cm: float
    wt_gf_cm_per_cm2: float
    lt: float
    rt_percent: float | None  # None without an unloading branch


@dataclass(frozen=True)
class BendingSummary:
    """KES-FB2 values of a loop; None where the loop does not reach the curvatures used."""

    b_gf_cm2_per_cm: float | None
    hb2_gf_cm_per_cm: float | None


@dataclass(frozen=True)
class KesFit:
    """Everything fitted to one KES-FB1 and one KES-FB2 loop."""

    tensile_loop: TensileLoop
    bending_loop: BendingLoop
    tensile: TensileFit
    bending: BendingFit
    tensile_kes: TensileSummary
    bending_kes: BendingSummary

    def material(self, name: str, density_g_per_cm2: float) -> dict:
        """The scene [material] fields (KES units); density and name come from elsewhere."""
        return {
            "name": name,
            "density_g_per_cm2": float(density_g_per_cm2),
            "tensile_gf_per_cm": [float(a) for a in self.tensile.coefficients],
            "bending_rigidity_gf_cm2_per_cm": float(self.bending.rigidity_gf_cm2_per_cm),
            "hysteresis_d1_gf_cm_per_cm": float(self.bending.d1_gf_cm_per_cm),
            "hysteresis_alpha_cm": float(self.bending.alpha_cm),
            "hysteresis_k0_per_cm": float(self.bending.k0_per_cm),
        }

    def summary_table(self) -> dict:
        """The [fit] table of a material file: residuals and KES values (omitted where undefined)."""
        t, b, tk, bk = self.tensile, self.bending, self.tensile_kes, self.bending_kes
        table = {
            "tensile_file": self.tensile_loop.source,
            "tensile_first_column": self.tensile_loop.strain_unit,
            "tensile_loading_points": len(self.tensile_loop.strain[self.tensile_loop.loading]),
            "tensile_rms_gf_per_cm": t.rms_gf_per_cm,
            "tensile_rms_relative": t.rms_relative,
            "tensile_constrained": t.constrained,
            "bending_file": self.bending_loop.source,
            "bending_points": len(self.bending_loop.curvature),
            "bending_rms_gf_cm_per_cm": b.rms_gf_cm_per_cm,
            "bending_rms_relative": b.rms_relative,
            "emt_percent": tk.emt_percent,
            "fm_gf_per_cm": tk.fm_gf_per_cm,
            "wt_gf_cm_per_cm2": tk.wt_gf_cm_per_cm2,
            "lt": tk.lt,
            "rt_percent": tk.rt_percent,
            "b_gf_cm2_per_cm": bk.b_gf_cm2_per_cm,
            "2hb_gf_cm_per_cm": bk.hb2_gf_cm_per_cm,
        }
        return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in table.items() if v is not None}


# ---------------------------------------------------------------------------------- reading


def _tokens(name: str) -> list[str]:
    text = name.lower().replace("%", " percent ").replace("/", " per ")
    return re.findall(r"[a-z0-9]+", text)


def _read_columns(path: str | Path, what: str) -> tuple[list[str] | None, np.ndarray, np.ndarray]:
    # Two numeric columns, comma, semicolon or whitespace separated; with ';' a ',' is
    # a decimal comma. Returns (header or None, values [n, 2], file line of each row).
    path = bundled_data(path)
    try:
        lines = read_text(path).splitlines()
    except OSError as exc:
        raise SceneError(str(path), f"cannot read the {what} file: {exc.strerror}") from None
    header = None
    values, rows = [], []
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if ";" in text:
            fields = [f.strip().replace(",", ".") for f in text.split(";")]
        elif "," in text:
            fields = [f.strip() for f in text.split(",")]
        elif "\t" in text:  # tab-separated: names may contain spaces ("Strain (%)")
            fields = [f.strip() for f in text.split("\t")]
        else:
            fields = text.split()
        while fields and not fields[-1]:
            fields.pop()  # a trailing separator, as spreadsheets write
        if header is None and not values:
            try:
                float(fields[0])
            except ValueError:
                if len(fields) != 2:
                    raise SceneError(str(path), f"line {number}: the header {text!r} has {len(fields)} column names, "
                                     "expected 2 (with whitespace separation a name cannot contain spaces)") from None
                header = fields
                continue
        if len(fields) != 2:
            raise SceneError(str(path), f"line {number}: expected 2 columns, got {len(fields)}: {text!r}")
        row = []
        for f in fields:
            try:
                row.append(float(f))
            except ValueError:
                raise SceneError(str(path), f"line {number}: {f!r} is not a number") from None
        values.append(row)
        rows.append(number)
    return header, np.array(values, dtype=np.float64).reshape(-1, 2), np.array(rows, dtype=int)


def _check_name(path: str | Path, column: int, name: str, words: set[str], units_ok: list[set[str]],
                expected: str) -> set[str]:
    # The column's name must be one of ``words`` and any unit it states one of ``units_ok``;
    # returns the unit tokens (what is left of the name).
    tokens = _tokens(name)
    unit = set(tokens) - words - {"per", "width", "of"}
    if not set(tokens) & words or (unit and unit not in units_ok):
        raise SceneError(str(path), f"header: column {column} is {name!r}; expected {expected}")
    return unit


def read_tensile_csv(path: str | Path, strain_unit: str | None = None,
                     gauge_length_mm: float = KES_FB1_GAUGE_MM) -> TensileLoop:
    """Read a KES-FB1 loop: columns strain (%, fraction) or extension (mm), force per width (gf/cm).

    ``path`` may also name a bundled example (``kes_fb1_example``).

    The first column's unit: the header's when it says, else ``strain_unit`` (percent,
    fraction, mm), else percent when its maximum exceeds 1 and a fraction otherwise.
    """
    if strain_unit is not None and strain_unit not in _STRAIN_UNITS:
        raise SceneError("--strain-unit", f"must be one of {', '.join(_STRAIN_UNITS)}; got {strain_unit!r}")
    if not (math.isfinite(gauge_length_mm) and gauge_length_mm > 0):
        raise SceneError("--gauge-length-mm", f"must be a positive length in mm, got {gauge_length_mm!r}")
    header, values, rows = _read_columns(path, "KES-FB1 tensile")
    unit = strain_unit
    if header is not None:
        first = _check_name(path, 1, header[0], _TENSILE_NAMES[0],
                            [{"percent"}, {"pct"}, {"fraction"}, {"frac"}, {"mm"}],
                            "strain_percent, strain_fraction, strain or extension_mm")
        _check_name(path, 2, header[1], _TENSILE_NAMES[1], [{"gf", "cm"}], "force per width in gf/cm "
                    "(e.g. force_gf_per_cm; a KES-FB2 bending file has curvature and moment)")
        said = {"percent": "percent", "pct": "percent", "fraction": "fraction", "frac": "fraction",
                "mm": "mm"}.get(next(iter(first), ""))
        if said is None and set(_tokens(header[0])) & {"extension", "elongation"}:
            said = strain_unit
            if said != "mm":
                raise SceneError(str(path), f"header: column 1 is {header[0]!r}: say its unit (extension_mm) or "
                                 "give strain_unit='mm'")
        if said and strain_unit and said != strain_unit:
            raise SceneError(str(path), f"header: column 1 {header[0]!r} says {said}, but the strain unit was "
                             f"given as {strain_unit}")
        unit = said or strain_unit
    _check_finite(values, rows, str(path), ("strain", "force"))
    how = "from the header" if header is not None and unit != strain_unit else "as given"
    if unit is None:
        unit = "percent" if len(values) and np.max(values[:, 0]) > 1 else "fraction"
        how = "guessed: the column's maximum is " + ("above" if unit == "percent" else "at most") + " 1"
    scale = {"percent": PERCENT, "fraction": 1.0, "mm": 1.0 / gauge_length_mm}[unit]
    loop = tensile_loop(values[:, 0] * scale, values[:, 1], source=str(path), rows=rows)
    described = f"extension in mm over a {gauge_length_mm:g} mm gauge" if unit == "mm" else f"strain in {unit}"
    return dataclasses.replace(loop, strain_unit=f"{described} ({how})")


def read_bending_csv(path: str | Path) -> BendingLoop:
    """Read a KES-FB2 loop: columns curvature (1/cm) and moment per width (gf·cm/cm).

    ``path`` may also name a bundled example (``kes_fb2_example``).
    """
    header, values, rows = _read_columns(path, "KES-FB2 bending")
    if header is not None:
        _check_name(path, 1, header[0], _BENDING_NAMES[0], [{"cm"}, {"1", "cm"}],
                    "curvature in 1/cm (e.g. curvature_per_cm; a KES-FB1 tensile file has strain and force)")
        _check_name(path, 2, header[1], _BENDING_NAMES[1], [{"gf", "cm"}],
                    "moment per width in gf·cm/cm (e.g. moment_gf_cm_per_cm)")
    _check_finite(values, rows, str(path), ("curvature", "moment"))
    return bending_loop(values[:, 0], values[:, 1], source=str(path), rows=rows)


def _check_finite(values: np.ndarray, rows: np.ndarray, source: str, names: tuple[str, str],
                  label: str = "line") -> None:
    bad = np.nonzero(~np.isfinite(values))
    if len(bad[0]):
        i, j = int(bad[0][0]), int(bad[1][0])
        raise SceneError(source, f"{label} {rows[i]}: {names[j]} is {values[i, j]}; every value must be finite")


def _paired(x: np.ndarray, y: np.ndarray, rows: np.ndarray | None, source: str,
            names: tuple[str, str]) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    # Two equally long finite columns, and where each row came from (file line or sample).
    x = np.asarray(x, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    label = "line" if rows is not None else "sample"
    rows = np.arange(1, len(x) + 1) if rows is None else np.asarray(rows)
    if len(x) != len(y):
        raise SceneError(source, f"{len(x)} {names[0]}s but {len(y)} {names[1]}s")
    _check_finite(np.column_stack([x, y]), rows, source, names, label)
    return x, y, rows, label


def tensile_loop(strain: np.ndarray, force: np.ndarray, source: str = "tensile data",
                 rows: np.ndarray | None = None) -> TensileLoop:
    """A validated tensile loop from arrays: strain as a fraction, force per width in gf/cm.

    Loading runs from the first point to the maximum strain and must not go back in strain;
    unloading, if any, must not go forward.
    """
    strain, force, rows, label = _paired(strain, force, rows, source, ("strain", "force"))
    loop = TensileLoop(strain, force, rows, source, label)
    n_loading = loop.turn + 1 if len(strain) else 0
    if n_loading < MIN_LOADING_POINTS:
        raise SceneError(source, f"the loading branch (first row to the maximum strain) has {n_loading} point(s); "
                         f"fitting the quartic needs at least {MIN_LOADING_POINTS}")
    if not strain[loop.turn] > 0:
        raise SceneError(source, f"the strain never exceeds 0 (maximum {strain[loop.turn]:g})")
    for part, sign, what in ((loop.loading, 1, "loading"), (loop.unloading, -1, "unloading")):
        index = np.arange(len(strain))[part]
        step = sign * np.diff(strain[part])
        if np.any(step < 0):
            i = int(index[np.nonzero(step < 0)[0][0]])
            raise SceneError(source, f"{label} {rows[i + 1]}: strain {strain[i + 1]:.6g} after {strain[i]:.6g} "
                             f"({label} {rows[i]}): the {what} branch must be monotonic in strain (loading runs "
                             f"to the maximum strain, {strain[loop.turn]:.6g} at {label} {rows[loop.turn]})")
    return loop


def bending_loop(curvature: np.ndarray, moment: np.ndarray, source: str = "bending data",
                 rows: np.ndarray | None = None) -> BendingLoop:
    """A validated bending loop from arrays: curvature in 1/cm, moment per width in gf·cm/cm.

    One cycle from rest: it must reach both signs of curvature (each at least half the
    largest |K|) and end within 10 % of the largest |K| of where it started.
    """
    curvature, moment, rows, label = _paired(curvature, moment, rows, source, ("curvature", "moment"))
    if len(curvature) < MIN_BENDING_POINTS:
        raise SceneError(source, f"the loop has {len(curvature)} point(s); fitting D, D1 and α along "
                         f"0 → +K0 → −K0 → 0 needs at least {MIN_BENDING_POINTS}")
    loop = BendingLoop(curvature, moment, rows, source, label)
    k0 = loop.k0
    if not k0 > 0:
        raise SceneError(source, "the curvature is 0 throughout")
    low, high = float(curvature.min()), float(curvature.max())
    if high < LOOP_REACH * k0 or low > -LOOP_REACH * k0:
        raise SceneError(source, f"the loop does not reach both signs of curvature: K runs from {low:.4g} to "
                         f"{high:.4g} 1/cm; a KES-FB2 loop goes to +K0 and −K0 (each side at least "
                         f"{LOOP_REACH:.0%} of the largest |K|)")
    if abs(curvature[0]) > LOOP_CLOSURE * k0:
        raise SceneError(source, f"the loop starts at K = {curvature[0]:.4g} 1/cm ({label} {rows[0]}), not from "
                         "rest: the model's hinge starts fresh at the first row, as a KES-FB2 cycle does from K = 0; "
                         "give the cycle from its start")
    gap = abs(curvature[-1] - curvature[0])
    if gap > LOOP_CLOSURE * k0:
        raise SceneError(source, f"the loop does not close: it starts at K = {curvature[0]:.4g} 1/cm ({label} "
                         f"{rows[0]}) and ends at K = {curvature[-1]:.4g} 1/cm ({label} {rows[-1]}); a KES-FB2 loop "
                         f"returns to its start (within {LOOP_CLOSURE:.0%} of the largest |K|, {k0:.4g} 1/cm)")
    return loop


# ---------------------------------------------------------------------------------- fitting


def _nnls(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # Lawson & Hanson's active-set algorithm: min ‖a x − b‖ subject to x ≥ 0.
    m, n = a.shape
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    tol = 10 * np.finfo(float).eps * np.linalg.norm(a, 1) * max(m, n)
    for _ in range(3 * n + 10):
        w = np.where(passive, -np.inf, a.T @ (b - a @ x))
        if passive.all() or np.max(w) <= tol:
            break
        passive[int(np.argmax(w))] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.lstsq(a[:, passive], b, rcond=None)[0]
            if np.all(z[passive] > 0):
                x = z
                break
            # step back towards x until the first variable reaches 0, and free it
            blocking = np.nonzero(passive & (z <= 0))[0]
            ratios = x[blocking] / (x[blocking] - z[blocking])
            x = x + np.min(ratios) * (z - x)
            x[blocking[np.argmin(ratios)]] = 0.0
            passive &= x > 0
            x[~passive] = 0.0
    return x


def _least_squares_above(a: np.ndarray, b: np.ndarray, g: np.ndarray, h: np.ndarray) -> np.ndarray:
    # min ‖a x − b‖ subject to g x ≥ h (a of full column rank), via the least-distance
    # problem and NNLS (Lawson & Hanson, ch. 23). Raises if the constraints are infeasible.
    q, r = np.linalg.qr(a)
    rinv = np.linalg.inv(r)
    y0 = q.T @ b  # x = rinv (z + y0); minimise ‖z‖ subject to (g rinv) z ≥ h − g rinv y0
    gz = g @ rinv
    hz = h - gz @ y0
    norms = np.linalg.norm(gz, axis=1, keepdims=True)  # same constraints, comparable scales
    gz, hz = gz / norms, hz / norms[:, 0]
    e = np.vstack([gz.T, hz[None, :]])
    f = np.zeros(e.shape[0])
    f[-1] = 1.0
    u = _nnls(e, f)
    residual = e @ u - f
    if np.linalg.norm(residual) < 1e-12:
        raise ValueError("the constraints are infeasible")
    z = -residual[:-1] / residual[-1]
    return rinv @ (z + y0)


def fit_tensile(loop: TensileLoop, max_strain: float = DIVERGENCE_STRAIN) -> TensileFit:
    """Least-squares quartic T(ε) = a1 ε + … + a4 ε⁴ through the loading branch.

    If it does not increase on [0, max(ε_max, max_strain)] (a scene needs it to, up to
    its divergence strain), the fit is redone with dT/dε ≥ 10⁻³ Fm/εm on 257 points of
    that range, and ``note`` says where the unconstrained fit failed.
    """
    e = loop.strain[loop.loading]
    t = loop.force[loop.loading]
    scale = float(e.max())
    powers = np.arange(1, 5)
    design = (e[:, None] / scale) ** powers
    unscale = scale ** -powers.astype(float)
    coefficients = np.linalg.lstsq(design, t, rcond=None)[0] * unscale
    upper = max(scale, max_strain)
    slope, where = tensile_slope_minimum(list(coefficients), upper)
    constrained, note = False, ""
    if not slope > 0:
        inside = "inside the data" if where <= scale else "beyond the data"
        free_rms = float(np.sqrt(np.mean((design @ (coefficients / unscale) - t) ** 2)))
        note = (f"the unconstrained quartic (RMS {free_rms:.3g} gf/cm) decreases at ε = {where:.4g} ({inside}, "
                f"which end at {scale:.4g}; dT/dε = {slope:.4g} gf/cm); refitted with dT/dε ≥ {SLOPE_FLOOR:g} "
                f"Fm/εm on [0, {upper:g}] (a smaller divergence strain constrains less)")
        grid = np.linspace(0.0, upper, 257) / scale
        # dT/dε = Σ k b_k (ε/s)^(k−1) / s for the scaled coefficients b_k
        gradient = powers * grid[:, None] ** (powers - 1) / scale
        floor = SLOPE_FLOOR * abs(loop.force[loop.turn]) / scale
        coefficients = _least_squares_above(design, t, gradient, np.full(len(grid), floor)) * unscale
        constrained = True
        slope, where = tensile_slope_minimum(list(coefficients), upper)
        if not slope > 0:  # pragma: no cover - the grid constraint holds between its points
            raise SceneError(loop.source, f"no increasing quartic fits the loading branch ({note})")
    rms = float(np.sqrt(np.mean((design @ (coefficients / unscale) - t) ** 2)))
    return TensileFit([float(a) for a in coefficients], rms, rms / (float(np.ptp(t)) or 1.0), constrained, note)


def hysteretic_offsets(curvature_per_cm: np.ndarray, alphas_cm: np.ndarray, k0_per_cm: float,
                       device: str | None = "cpu") -> np.ndarray:
    """Offset h(α; path) per gf·cm/cm of D1 along a curvature path, one column per α.

    All α run in one kernel launch (warpcloth.bending.moment_along_path, the strip
    kernel's hinge logic) with D = 0 and D1 = 1 gf·cm/cm; the hinge starts fresh at the
    path's first sample. Returns ``[sample, alpha]``, in gf·cm/cm per gf·cm/cm of D1.
    """
    materials = [MaterialSI(density=1.0, tensile=(0.0, 0.0, 0.0, 0.0), bending_rigidity=0.0,
                            hysteresis_d1=units.MOMENT_GF_CM_PER_CM, hysteresis_alpha=float(a) * units.LENGTH_CM,
                            hysteresis_k0=k0_per_cm * units.CURVATURE_PER_CM) for a in np.atleast_1d(alphas_cm)]
    k = np.asarray(curvature_per_cm, dtype=np.float64) * units.CURVATURE_PER_CM
    moment, _ = moment_along_path(materials, k[:, None], device=device)
    return moment / units.MOMENT_GF_CM_PER_CM


def _linear_part(curvature: np.ndarray, moment: np.ndarray, offset: np.ndarray) -> tuple[float, float, float]:
    # D, D1 ≥ 0 of M = D K + D1 h for one α, and the sum of squared residuals.
    d, d1 = _nnls(np.column_stack([curvature, offset]), moment)
    return float(d), float(d1), float(np.sum((d * curvature + d1 * offset - moment) ** 2))


def fit_bending(loop: BendingLoop, device: str | None = "cpu") -> BendingFit:
    """Fit D, D1 and α of M = D K + h to the whole loop (K0 = the loop's largest |K|).

    For each α, (D, D1) is a linear least-squares problem; α comes from a log grid of
    α K0 (one kernel launch) refined by golden-section search on log α.
    """
    k, m, k0 = loop.curvature, loop.moment, loop.k0
    low, high, n = ALPHA_K0_GRID
    grid = np.geomspace(low, high, n) / k0
    offsets = hysteretic_offsets(k, grid, k0, device)
    sse = np.array([_linear_part(k, m, offsets[:, i])[2] for i in range(n)])
    best = int(np.argmin(sse))
    note = ""
    if best in (0, n - 1):
        note = (f"α at the edge of its search range (α K0 = {grid[best] * k0:g}); the loop may not have the "
                "model's shape")

    def objective(log_alpha: float) -> float:
        return _linear_part(k, m, hysteretic_offsets(k, [math.exp(log_alpha)], k0, device)[:, 0])[2]

    # golden section on log α between the best grid point's neighbours
    a, b = math.log(grid[max(best - 1, 0)]), math.log(grid[min(best + 1, n - 1)])
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - ratio * (b - a), a + ratio * (b - a)
    fc, fd = objective(c), objective(d)
    while b - a > 1e-10:
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - ratio * (b - a)
            fc = objective(c)
        else:
            a, c, fc = c, d, fd
            d = a + ratio * (b - a)
            fd = objective(d)
    alpha = math.exp(0.5 * (a + b))
    if sse[best] < min(fc, fd):  # a flat objective (no hysteresis): keep the grid's point
        alpha = float(grid[best])
    offset = hysteretic_offsets(k, [alpha], k0, device)[:, 0]
    d_fit, d1_fit, total = _linear_part(k, m, offset)
    if d1_fit == 0.0:
        note = "the loop shows no hysteresis (D1 = 0): α has no effect"
    rms = math.sqrt(total / len(k))
    return BendingFit(d_fit, d1_fit, alpha, k0, rms, rms / (float(np.ptp(m)) or 1.0),
                      d_fit * k + d1_fit * offset, note)


# ---------------------------------------------------------------------------------- KES values


def _area(y: np.ndarray, x: np.ndarray) -> float:
    # trapezoid rule (np.trapezoid needs NumPy 2; warpcloth supports 1.24)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def tensile_summary(loop: TensileLoop) -> TensileSummary:
    """EMT, Fm, WT, LT and (with unloading data) RT of a tensile loop."""
    e, t = loop.strain, loop.force
    load, unload = loop.loading, loop.unloading
    em, fm = float(e[loop.turn]), float(t[loop.turn])
    wt = _area(t[load], e[load])
    lt = wt / (0.5 * fm * em)
    rt = None
    if len(e[unload]) > 1:
        rt = 100.0 * _area(t[unload][::-1], e[unload][::-1]) / wt
    return TensileSummary(em / PERCENT, fm, wt, lt, rt)


def _branch_value(k: np.ndarray, m: np.ndarray, at: float) -> float | None:
    # M of one leg at curvature ``at``: a line through its points within the window, or
    # linear interpolation; None when the leg does not reach ``at``.
    if not k.min() <= at <= k.max():
        return None
    near = np.abs(k - at) <= HB_WINDOW_PER_CM
    if np.count_nonzero(near) >= 3 and np.ptp(k[near]) > 0:
        slope, intercept = np.polyfit(k[near], m[near], 1)
        return float(slope * at + intercept)
    order = np.argsort(k, kind="stable")
    return float(np.interp(at, k[order], m[order]))


def bending_summary(loop: BendingLoop) -> BendingSummary:
    """B and 2HB of a bending loop (None where the loop does not reach the curvatures used)."""
    k, m = loop.curvature, loop.moment
    legs = [(k[leg], m[leg], np.sign(k[leg][-1] - k[leg][0])) for leg in loop.legs()]
    slopes = {}
    for kl, ml, direction in legs:
        for side in (1.0, -1.0):
            inside = (side * kl >= B_RANGE_PER_CM[0]) & (side * kl <= B_RANGE_PER_CM[1])
            spans = np.min(side * kl) <= B_RANGE_PER_CM[0] and np.max(side * kl) >= B_RANGE_PER_CM[1]
            if spans and np.count_nonzero(inside) >= 3:
                slopes.setdefault((direction, side), []).append(np.polyfit(kl[inside], ml[inside], 1)[0])
    b = float(np.mean([s for v in slopes.values() for s in v])) if len(slopes) == 4 else None
    widths = []
    for at in (HB_CURVATURE_PER_CM, -HB_CURVATURE_PER_CM):
        values = {1.0: [], -1.0: []}
        for kl, ml, direction in legs:
            value = _branch_value(kl, ml, at)
            if value is not None and direction in values:
                values[direction].append(value)
        if values[1.0] and values[-1.0]:
            widths.append(np.mean(values[1.0]) - np.mean(values[-1.0]))
    hb2 = float(np.mean(widths)) if len(widths) == 2 else None
    return BendingSummary(b, hb2)


# ---------------------------------------------------------------------------------- together


def fit_kes(tensile: TensileLoop, bending: BendingLoop, max_strain: float = DIVERGENCE_STRAIN,
            device: str | None = "cpu") -> KesFit:
    """Fit the tensile quartic and the bending law, and compute the KES values of both loops."""
    return KesFit(tensile, bending, fit_tensile(tensile, max_strain), fit_bending(bending, device),
                  tensile_summary(tensile), bending_summary(bending))


def material_file_data(fit: KesFit, name: str, density_g_per_cm2: float, source: str,
                       max_strain: float = DIVERGENCE_STRAIN) -> dict:
    """The TOML data of a material file for a fit, checked usable up to ``max_strain``."""
    if not (math.isfinite(density_g_per_cm2) and density_g_per_cm2 > 0):
        raise SceneError("--density-g-per-cm2", f"must be a positive mass per area in g/cm², got "
                         f"{density_g_per_cm2!r}")
    material = fit.material(name, density_g_per_cm2)
    validate_material(MaterialSection(**material), max_strain, "material")
    ordered = {"name": name, "source": source, **{k: material[k] for k in material_fields() if k != "name"}}
    return {"material": ordered, "fit": fit.summary_table()}


def write_material_file(path: str | Path, data: dict) -> Path:
    """Write material file ``data`` (see :func:`material_file_data`) as TOML."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomically(path, tomli_w.dumps(data))
    return path


def plot_kes_fit(fit: KesFit, path: str | Path) -> Path:
    """PNG of the data against the fit: tensile (left) and bending (right), KES values in the titles."""
    from matplotlib.figure import Figure  # no pyplot: no global backend state

    path = Path(path)
    figure = Figure(figsize=(11, 4.6), dpi=120, layout="constrained")
    left, right = figure.subplots(1, 2)
    tl, tk, tf = fit.tensile_loop, fit.tensile_kes, fit.tensile
    left.plot(tl.strain / PERCENT, tl.force, ".", ms=3, color="0.4", label="data")
    e = np.linspace(0.0, float(tl.strain.max()), 200)
    left.plot(e / PERCENT, tf(e), "-", color="C0", label="quartic fit (loading)")
    rt = f", RT {tk.rt_percent:.1f} %" if tk.rt_percent is not None else ""
    left.set_title(f"KES-FB1: EMT {tk.emt_percent:.2f} %, LT {tk.lt:.3f}, WT {tk.wt_gf_cm_per_cm2:.3g} "
                   f"gf·cm/cm²{rt}", fontsize=9)
    left.set_xlabel("strain (%)")
    left.set_ylabel("force per width T (gf/cm)")
    a = ", ".join(f"{c:.4g}" for c in tf.coefficients)
    left.text(0.03, 0.97, f"a = ({a}) gf/cm\nRMS {tf.rms_gf_per_cm:.3g} gf/cm ({tf.rms_relative:.2%} of range)"
              + ("\nconstrained to increase" if tf.constrained else ""),
              transform=left.transAxes, va="top", fontsize=8, bbox={"fc": "white", "alpha": 0.8})
    left.legend(loc="lower right", fontsize=8)
    bl, bk, bf = fit.bending_loop, fit.bending_kes, fit.bending
    right.plot(bl.curvature, bl.moment, ".", ms=3, color="0.4", label="data")
    right.plot(bl.curvature, bf.moment, "-", color="C3", label="model fit")
    b = f"{bk.b_gf_cm2_per_cm:.4g}" if bk.b_gf_cm2_per_cm is not None else "n/a"
    hb = f"{bk.hb2_gf_cm_per_cm:.4g}" if bk.hb2_gf_cm_per_cm is not None else "n/a"
    right.set_title(f"KES-FB2: B {b} gf·cm²/cm, 2HB {hb} gf·cm/cm", fontsize=9)
    right.set_xlabel("curvature K (1/cm)")
    right.set_ylabel("moment per width M (gf·cm/cm)")
    right.text(0.03, 0.97, f"D {bf.rigidity_gf_cm2_per_cm:.4g} gf·cm²/cm, D1 {bf.d1_gf_cm_per_cm:.4g} gf·cm/cm\n"
               f"α {bf.alpha_cm:.4g} cm, K0 {bf.k0_per_cm:.4g} 1/cm\n"
               f"RMS {bf.rms_gf_cm_per_cm:.3g} gf·cm/cm ({bf.rms_relative:.2%} of range)",
               transform=right.transAxes, va="top", fontsize=8, bbox={"fc": "white", "alpha": 0.8})
    right.legend(loc="lower right", fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    return path
