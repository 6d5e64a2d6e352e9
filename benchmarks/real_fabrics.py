"""The woven sheet's bias cantilever against real fabrics' bending on the bias (run by hand).

    PYTHONPATH=. python benchmarks/real_fabrics.py [--csv PATH] [--spacing-mm 5] [--limit N]
                                                   [--fine-count 12] [--shear-count 8]

The fabrics: Feng et al., SIGGRAPH Asia 2022, "Learning-based bending stiffness parameter
estimation by a drape tester" (github.com/DrapeTester/ClothDrapeTester, dataset/dataset.csv,
not bundled: ``--csv`` or $WARPCLOTH_FENG2022_CSV), read by
:func:`warpcloth.calibrate.fabric_dataset.read_feng2022` (251 distinct fabrics): areal
density ρ_A and the linear bending stiffness k1 (N·m, a moment per width k1 κ) along the
warp, the weft and the diagonal, fitted from cantilever tests.

Each fabric becomes a sheet (:class:`warpcloth.sheet.SheetMaterialSI`): D11 = k1_warp,
D22 = k1_weft, the diagonal as the bias's rigidity (KES-FB2's wide sample: D(45°) =
(D11 + 2 D12 + 4 D66 + D22)/4), ν = 0 (D12 = 0, so 4 D66 = 4 k1_diag − D11 − D22; the
fabrics whose diagonal is below (warp + weft)/4 are refused and counted), elastic laws
(masing with hysteresis_d1 = 0, as the tests), a stiff tension a1 = 2000 N/m (no k2: the
fabrics' nonlinear terms are left out), and a shear rigidity the data do not give:
G = 0.5 gf/(cm·°) (28.1 N/(m·rad), a soft fabric's KES G); a second pass on a subset
multiplies and divides it by 10 to show that the result barely depends on it (a flat
strip's small bending does not shear its cells to first order).

The measurement, as tests/test_plate_bending.py's ``cantilever_mode``: a strip cut at 45°
to the warp (:func:`warpcloth.sheet.bias_strip`), clamped at its top edge, no gravity,
displaced by 1 µm into Euler-Bernoulli's first cantilever mode and let go; ω from the
mean displacement of the tip's row of nodes (a twist about the strip's axis cancels in
it), over 1.6 reference periods (three zero crossings; the reference rigidity
√(B_narrow D(45°)), between which B_eff lies): the crossings' mean spacing, refined by a
least-squares fit of a cos ωt + b sin ωt + c over the whole record (the crossings alone
moved B_eff by 0.4 % with the run's length on strongly coupled fabrics, the fit 0.1 %),
corrected by symplectic Euler's own frequency map (ω_true = √(2 − 2 cos(ω_run dt)) / dt). Its
length and width are whole cell diagonals h√2, 8 and 4 of them at h = 5 mm (56.6 mm ×
28.3 mm), so that on the 45° lattice the sides and the tip run through nodes and every
cut cell is a half (a side crossing cells at random would add an O(h) error of its own,
as the 22.5° cuts in the tests show); the same physical strip at every spacing. Then

    B_eff = ω² ρ_A L⁴ / 1.8751⁴,   c_eff = (B_eff / (ρ_A g))^(1/3)

against the data's diagonal c_data = (k1_diag / (ρ_A g))^(1/3), with the relative error of
c (a third of B's, to first order) and of B.

The narrow-beam reference. Curvatures κ = (κ11, κ22, 2κ12) (engineering twist) and the
moments per width M = D κ, D = [[D11, D12, 0], [D12, D22, 0], [0, 0, D66]] (energy
½ κ·D κ = ½ (D11 κ11² + 2 D12 κ11 κ22 + D22 κ22² + 4 D66 κ12²)). In axes turned by θ,
κ' = T κ with T = [[c², s², cs], [s², c², −cs], [−2cs, 2cs, c² − s²]] (curvatures turn
as strains), so D' = T⁻ᵀ D T⁻¹ and the compliance S = D⁻¹ turns as S' = T S Tᵀ. A wide
sample held in cylindrical bending (κ'22 = κ'12 = 0) costs D'11 = D(θ): at 45° the
data's k1_diag, by construction. A narrow strip with free edges carries M'22 = M'12 = 0,
so κ'11 = S'11 M'11: B_narrow = 1/S'11, and at 45° (T's first row ½ (1, 1, 1))

    S'11 = (S11 + 2 S12 + S22 + S66)/4,
    B_narrow(45°) = 4 / ((D11 + D22 − 2 D12)/(D11 D22 − D12²) + 1/D66)
                  = 4 / (1/D11 + 1/D22 + 1/D66)                    (ν = 0).

It is below D(45°) for two reasons the script splits: the strip's anticlastic curvature
(D'12 ≠ 0; with ν = 0, D'12 = (D11 + D22)/2 − k1_diag), B_anticlastic = D'11 − D'12²/D'22
with the twist held, and its bending-twisting coupling (D'16 = (D22 − D11)/4, zero for a
balanced fabric: a bias strip of a fabric whose warp and weft differ twists as it bends),
B_twist = D'11 − D'16²/D'66 with the cross curvature held; both free give B_narrow.
(D'66 = (D11 + D22)/4 at ν = 0.) KES's wide sample does neither; the cantilever
strips of the data were narrow. The finite strip here (L/W = 2, its root held by the
clamp) lies between B_narrow and D(45°); a finer spacing on a subset (``--fine-count``
fabrics at h/2) shows how much of B_eff/B_narrow − 1 is discretisation.

Prints the machine, progress with rate and ETA, then the distributions (numpy's
percentiles, linear rule) over the fabrics built.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.optimize
import warp as wp

from warpcloth import units
from warpcloth.calibrate.fabric_dataset import STANDARD_GRAVITY, FabricRecord, bending_length, read_feng2022
from warpcloth.errors import ArgumentError, WarpclothError
from warpcloth.sheet import SheetBuilder, SheetMaterialSI, SheetRecorder, SheetSolver, bias_strip, simulate_sheets
from warpcloth.strip import LawParameters, MaterialSI
from warpcloth.strip.model import init_warp_quietly

ELASTIC = LawParameters.of("masing", {"hysteresis_d1": 0.0, "hysteresis_alpha": 10.0, "hysteresis_k0": 1.0})
BETA = 1.8751040687  # the cantilever's first root
A1 = 2000.0  # N/m: tension, stiff (a1 L² / k1_diag ≥ 2e4 on every fabric)
SHEAR_G_KES = 0.5  # gf/(cm·°): G, not in the data
SHEAR_FACTORS = (0.1, 10.0)  # the G-sensitivity pass
LENGTH_DIAGONALS, WIDTH_DIAGONALS = 8, 4  # at --spacing-mm; the same strip at h/2
PERIODS = 1.6  # of the reference period: crossings at T/4, 3T/4, 5T/4
SAMPLES_PER_PERIOD = 400


@dataclass
class Mode:
    """One cantilever run: the effective rigidity B_eff (N·m) or NaN, and its wall time."""

    rigidity: float
    seconds: float
    steps: int


def rotated_rigidity(d11: float, d22: float, d12: float, d66: float, theta: float) -> np.ndarray:
    """D' = T⁻ᵀ D T⁻¹ in axes turned by θ (engineering twist 2κ12, see the docstring)."""
    c, s = math.cos(theta), math.sin(theta)
    t = np.array([[c * c, s * s, c * s], [s * s, c * c, -c * s], [-2 * c * s, 2 * c * s, c * c - s * s]])
    d = np.array([[d11, d12, 0.0], [d12, d22, 0.0], [0.0, 0.0, d66]])
    t_inv = np.linalg.inv(t)
    return t_inv.T @ d @ t_inv


def plate_references(material: SheetMaterialSI) -> tuple[float, float, float, float]:
    """(D(45°), B_anticlastic, B_twist, B_narrow) of the plate: the wide sample's cylindrical
    bending, the strip free to curve across its width but held from twisting, free to twist
    but held from curving across, and free of both (1/S'11)."""
    d11, d22 = material.warp.bending_rigidity, material.weft.bending_rigidity
    d12, d66 = material.poisson_coupling, material.twist_law()[0] / 4
    dp = rotated_rigidity(d11, d22, d12, d66, math.pi / 4)
    wide = dp[0, 0]
    anticlastic = dp[0, 0] - dp[0, 1] ** 2 / dp[1, 1]
    twist = dp[0, 0] - dp[0, 2] ** 2 / dp[2, 2]
    if d66 <= 0.0:
        return wide, anticlastic, twist, 0.0
    narrow = 1.0 / np.linalg.inv(dp)[0, 0]
    # the closed form of the docstring (ν = 0 or not)
    closed = 4.0 / ((d11 + d22 - 2 * d12) / (d11 * d22 - d12 * d12) + 1.0 / d66)
    assert abs(narrow / closed - 1) < 1e-9, (narrow, closed)
    return wide, anticlastic, twist, narrow


def sheet_material(fabric: FabricRecord, shear_kes: float) -> SheetMaterialSI:
    """The fabric's sheet (raises ArgumentError("bias", …) when 4 D66 would be negative)."""

    def line(rigidity: float) -> MaterialSI:
        return MaterialSI(
            density=fabric.areal_density, tensile=(A1, 0.0, 0.0, 0.0), bending_rigidity=rigidity, bending=ELASTIC
        )

    g = shear_kes * units.SHEAR_RIGIDITY_GF_PER_CM_DEG
    return SheetMaterialSI(
        line(fabric.rigidity_warp), line(fabric.rigidity_weft), g, ELASTIC, line(fabric.rigidity_diagonal), 0.0
    )


def frequency(t: np.ndarray, u: np.ndarray) -> float:
    """ω from the mean spacing of u's zero crossings (each interpolated linearly); NaN
    with fewer than two crossings."""
    z = np.flatnonzero(np.sign(u[:-1]) * np.sign(u[1:]) < 0)
    if len(z) < 2:
        return math.nan
    crossings = t[z] - u[z] * (t[z + 1] - t[z]) / (u[z + 1] - u[z])
    return math.pi / float(np.mean(np.diff(crossings)))


def fitted_frequency(t: np.ndarray, u: np.ndarray, guess: float) -> float:
    """ω of the least-squares fit u ≈ a cos ωt + b sin ωt + c over the whole record (a and
    b and c solved for each ω), searched within ±20 % of ``guess``: less sensitive than the
    crossings to the higher modes the initial shape also excites."""

    def residual(omega: float) -> float:
        basis = np.stack([np.cos(omega * t), np.sin(omega * t), np.ones_like(t)], axis=1)
        coefficients = np.linalg.lstsq(basis, u, rcond=None)[0]
        return float(np.sum((basis @ coefficients - u) ** 2))

    found = scipy.optimize.minimize_scalar(
        residual, bounds=(0.8 * guess, 1.2 * guess), method="bounded", options={"xatol": 1e-9 * guess}
    )
    return float(found.x)


def cantilever_rigidity(material: SheetMaterialSI, h: float, length: float, width: float, reference: float) -> Mode:
    """B_eff of the 45° strip's first bending mode (no gravity), ``reference`` (N·m) setting
    the run's duration and sampling; a run with fewer than three crossings is redone 2×
    longer."""
    start = time.perf_counter()
    geometry = bias_strip(length, width, h, h, angle=math.pi / 4)
    builder = SheetBuilder(geometry, gravity=0.0)
    builder.add_sheet(material, damping=0.0)
    model = builder.finalize(device="cpu")
    solver = SheetSolver(model, 0.5 * SheetSolver(model, 1.0).stable_step())
    rest = geometry.rest_positions
    s = (-rest[:, 1]).clip(0.0, None)
    bx = BETA * s / length
    ratio = (math.cosh(BETA) + math.cos(BETA)) / (math.sinh(BETA) + math.sin(BETA))
    shape = np.cosh(bx) - np.cos(bx) - ratio * (np.sinh(bx) - np.sin(bx))
    position = rest.copy()
    position[:, 0] += 1e-6 * shape / shape.max()
    # the tip's row of nodes, whose mean displacement cancels a twist about the strip's axis
    tip = tuple(int(i) for i in np.flatnonzero(np.abs(rest[:, 1] + length) < 1e-6 * h))
    rho = material.density
    period = 2 * math.pi / (BETA**2 * math.sqrt(reference / (rho * length**4)))
    steps = 0
    for stretch in (1, 2, 4):
        state = model.state()
        state.set_positions(position[:, None, :])
        duration = stretch * PERIODS * period
        recorder = SheetRecorder(period / SAMPLES_PER_PERIOD, 10**6, duration, markers=tip)
        run = simulate_sheets(model, model.control(), solver, recorder, state, keep_frames=False, threads=1)
        steps += round(duration / solver.dt)
        u = run.markers[:, 0, :, 0].mean(axis=1)
        if np.count_nonzero(np.sign(u[:-1]) * np.sign(u[1:]) < 0) >= 3:
            break
    omega_run = frequency(run.t, u)
    if math.isfinite(omega_run):
        omega_run = fitted_frequency(run.t, u, omega_run)
    # symplectic Euler turns ω into acos(1 − (ω dt)²/2)/dt; invert it
    omega = math.sqrt(2 - 2 * math.cos(omega_run * solver.dt)) / solver.dt
    return Mode(omega**2 * rho * length**4 / BETA**4, time.perf_counter() - start, steps)


class Progress:
    """``label k/n, rate /s, ETA`` on stderr every few seconds and at the end."""

    def __init__(self, label: str, total: int, every_s: float = 10.0) -> None:
        self.label, self.total, self.every_s = label, total, every_s
        self.start = self.last = time.perf_counter()

    def step(self, done: int) -> None:
        """Report ``done`` of the total if a while has passed or all are done."""
        now = time.perf_counter()
        if now - self.last < self.every_s and done < self.total:
            return
        self.last = now
        rate = done / (now - self.start)
        eta = (self.total - done) / rate if rate > 0 else math.inf
        print(
            f"  [{self.label}] {done}/{self.total}, {rate:.2f} /s, elapsed {now - self.start:.0f} s, ETA {eta:.0f} s",
            file=sys.stderr,
            flush=True,
        )


def spread(values: np.ndarray) -> str:
    """median, 10–90 %, min–max of ``values`` in %."""
    v = 100 * np.asarray(values)
    p = np.percentile(v, [0, 10, 50, 90, 100])
    return f"median {p[2]:+7.2f} %, 10–90 % {p[1]:+7.2f} … {p[3]:+7.2f} %, min–max {p[0]:+7.2f} … {p[4]:+7.2f} %"


def c_error(b: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """c_eff/c_ref − 1 = (B_eff/B_ref)^(1/3) − 1."""
    return np.cbrt(np.asarray(b) / np.asarray(reference)) - 1


def subset(n: int, k: int) -> list[int]:
    """``k`` indices spread evenly over 0 … n−1 (all of them if k ≥ n)."""
    return sorted({int(round(x)) for x in np.linspace(0, n - 1, min(k, n))})


def main() -> None:
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--csv", type=Path, default=None, help="dataset.csv (default: $WARPCLOTH_FENG2022_CSV)")
    parser.add_argument("--spacing-mm", type=float, default=5.0)
    parser.add_argument("--limit", type=int, default=None, help="the first N distinct fabrics only")
    parser.add_argument("--fine-count", type=int, default=12, help="fabrics rerun at half the spacing (0: none)")
    parser.add_argument("--shear-count", type=int, default=8, help="fabrics rerun at G ×0.1 and ×10 (0: none)")
    args = parser.parse_args()

    init_warp_quietly()
    cpu = platform.processor() or platform.machine()
    for line in Path("/proc/cpuinfo").read_text().splitlines() if Path("/proc/cpuinfo").exists() else []:
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
            break
    print(
        f"machine: {platform.platform()}, {cpu}, Python {platform.python_version()}, warp {wp.__version__}, "
        f"device cpu, float64, one thread; {time.strftime('%Y-%m-%d %H:%M')}"
    )
    fabrics = read_feng2022(args.csv)
    if args.limit is not None:
        fabrics = fabrics[: args.limit]
    h = args.spacing_mm * units.LENGTH_MM
    length, width = LENGTH_DIAGONALS * h * math.sqrt(2), WIDTH_DIAGONALS * h * math.sqrt(2)
    g_si = SHEAR_G_KES * units.SHEAR_RIGIDITY_GF_PER_CM_DEG
    print(
        f"{len(fabrics)} distinct fabrics; 45° strip {length * 1e3:.1f} × {width * 1e3:.1f} mm "
        f"({LENGTH_DIAGONALS} × {WIDTH_DIAGONALS} cell diagonals at h = {h * 1e3:g} mm), a1 = {A1:g} N/m, "
        f"G = {SHEAR_G_KES} gf/(cm·°) = {g_si:.3g} N/(m·rad), ν = 0, elastic laws, no gravity"
    )

    built: list[tuple[FabricRecord, SheetMaterialSI, tuple[float, float, float, float]]] = []
    refused = []
    for fabric in fabrics:
        try:
            material = sheet_material(fabric, SHEAR_G_KES)
        except ArgumentError as exc:
            if exc.argument != "bias":
                raise
            refused.append(fabric)
            continue
        built.append((fabric, material, plate_references(material)))
    print(
        f"refused (k1_diag < (k1_warp + k1_weft)/4: 4 D66 < 0 at ν = 0): {len(refused)} of {len(fabrics)} "
        f"({len(refused) / max(len(fabrics), 1):.1%}); built {len(built)}"
    )

    def measure(label: str, indices: list[int], spacing: float, shear_kes: float) -> np.ndarray:
        progress = Progress(label, len(indices))
        out = np.full(len(indices), math.nan)
        seconds = steps = 0
        for k, i in enumerate(indices):
            fabric, material, (wide, _anticlastic, _twist, narrow) = built[i]
            if shear_kes != SHEAR_G_KES:
                material = sheet_material(fabric, shear_kes)
            # B_eff lies between B_narrow and D(45°): their geometric mean sets the run's length
            reference = max(math.sqrt(narrow * wide), 0.25 * wide)
            mode = cantilever_rigidity(material, spacing, length, width, reference)
            out[k] = mode.rigidity
            seconds += mode.seconds
            steps += mode.steps
            progress.step(k + 1)
        print(f"  [{label}] {len(indices)} runs, {seconds:.0f} s, {steps / max(seconds, 1e-9):.3g} steps/s")
        return out

    everything = list(range(len(built)))
    b_eff = measure(f"h = {h * 1e3:g} mm", everything, h, SHEAR_G_KES)
    wide = np.array([r[0] for _, _, r in built])
    anticlastic = np.array([r[1] for _, _, r in built])
    twist = np.array([r[2] for _, _, r in built])
    narrow = np.array([r[3] for _, _, r in built])
    data = np.array([f.rigidity_diagonal for f, _, _ in built])
    assert np.allclose(wide, data, rtol=1e-9)  # D(45°) of the sheet is the data's diagonal by construction
    failed = ~np.isfinite(b_eff)
    ok = ~failed
    print(f"\nmeasured {ok.sum()} of {len(built)} (no frequency: {failed.sum()})")
    print(f"h = {h * 1e3:g} mm, all {ok.sum()} fabrics built:")
    print(f"  c_eff / c_data − 1         {spread(c_error(b_eff[ok], data[ok]))}")
    print(f"  B_eff / k1_diag − 1        {spread(b_eff[ok] / data[ok] - 1)}")
    print(f"  B_eff / B_narrow − 1       {spread(b_eff[ok] / narrow[ok] - 1)}")
    print(f"  B_narrow / k1_diag − 1     {spread(narrow / data - 1)}   (plate theory alone)")
    print(f"  B_anticlastic / k1_diag − 1 {spread(anticlastic / data - 1)}   (free to curve across, twist held)")
    print(f"  B_twist / k1_diag − 1      {spread(twist / data - 1)}   (free to twist, held across)")
    print(f"  c_narrow / c_data − 1      {spread(c_error(narrow, data))}")
    ratio = np.array([f.rigidity_warp / f.rigidity_weft for f, _, _ in built])
    print(f"  warp/weft k1: {spread(ratio - 1)} (as ratio − 1)")
    if ok.sum() >= 4:
        share = np.corrcoef(np.log(b_eff[ok] / data[ok]), np.log(narrow[ok] / data[ok]))[0, 1]
        print(f"  correlation of log(B_eff/k1_diag) with log(B_narrow/k1_diag): {share:.3f}")
    worst = np.argsort(-np.abs(np.where(ok, b_eff / data - 1, 0)))[:5]
    print("  largest |B_eff/k1_diag − 1|: line, ρ_A kg/m², k1 warp/weft/diag 1e-6 N·m, B_narrow/k1_diag, B_eff/k1_diag")
    for i in worst:
        f = built[i][0]
        print(
            f"    {f.line:4d}  {f.areal_density:.4f}  {f.rigidity_warp * 1e6:7.3f} {f.rigidity_weft * 1e6:7.3f} "
            f"{f.rigidity_diagonal * 1e6:7.3f}  {narrow[i] / data[i]:.4f}  {b_eff[i] / data[i]:.4f}"
        )
    c_data = np.array([bending_length(d, f.areal_density) for d, (f, _, _) in zip(data, built, strict=True)])
    lo, mid, hi = (1e3 * c_data.min(), 1e3 * np.median(c_data), 1e3 * c_data.max())
    print(f"  c_data (mm): median {mid:.1f}, min–max {lo:.1f}–{hi:.1f}")

    if args.shear_count > 0 and built:
        picks = [i for i in subset(len(built), args.shear_count) if ok[i]]
        print(f"\nG sensitivity on {len(picks)} fabrics spread over the list, h = {h * 1e3:g} mm:")
        for factor in SHEAR_FACTORS:
            other = measure(f"G ×{factor:g}", picks, h, SHEAR_G_KES * factor)
            change = other / b_eff[picks] - 1
            print(
                f"  G = {SHEAR_G_KES * factor:g} gf/(cm·°): B_eff(G)/B_eff({SHEAR_G_KES:g}) − 1 from "
                f"{change.min():+.2e} to {change.max():+.2e}"
            )

    if args.fine_count > 0 and built:
        picks = [i for i in subset(len(built), args.fine_count) if ok[i]]
        fine = measure(f"h = {h * 500:g} mm", picks, h / 2, SHEAR_G_KES)
        coarse = b_eff[picks]
        # Richardson at order 2 (the 0°/90° cantilever's; the 45° one's measured order is
        # 1.72 in tests/test_plate_bending.py)
        extrapolated = fine + (fine - coarse) / 3
        print(f"\nfiner spacing on {len(picks)} fabrics spread over the list (h = {h * 1e3:g} and {h * 500:g} mm):")
        for name, b in ((f"{h * 1e3:g} mm", coarse), (f"{h * 500:g} mm", fine), ("extrapolated, p = 2", extrapolated)):
            print(f"  {name}:")
            print(f"    c_eff / c_data − 1    {spread(c_error(b, data[picks]))}")
            print(f"    B_eff / k1_diag − 1   {spread(b / data[picks] - 1)}")
            print(f"    B_eff / B_narrow − 1  {spread(b / narrow[picks] - 1)}")
        print(f"  B({h * 500:g} mm)/B({h * 1e3:g} mm) − 1   {spread(fine / coarse - 1)}")
        print(f"  (same fabrics) B_narrow / k1_diag − 1  {spread(narrow[picks] / data[picks] - 1)}")
    print(f"\n(g = {STANDARD_GRAVITY} m/s²; c = (B / (ρ_A g))^(1/3))")


if __name__ == "__main__":
    try:
        main()
    except WarpclothError as exc:  # a missing or damaged dataset: one line, as warpcloth's commands say it
        print(f"real_fabrics.py: {exc}", file=sys.stderr)
        sys.exit(2)
