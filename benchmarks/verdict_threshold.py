"""Evidence for the one verdict threshold (issue 22): how far RMS / noise spreads for a
right model over noise seeds, and where models that are wrong show.

Every fit judges its RMS against the noise estimated from the data itself
(:func:`warpcloth.calibrate.noise.difference_noise`), so a right model's ratio spreads by
the RMS's own scatter and the estimator's. Measured here, each over ``--seeds`` seeds:

1. the estimator alone: sample σ / estimated σ of white noise, n = 60, 100, 200 and 500
   (5000 seeds: its spread, ≈ 1.46 / √n, and how often it passes the threshold);
2. the clamp-motion fit, right model: a record moving from its first sample (the
   issue's θ = a t² + b t³ + c t⁴ then a line at 2 rad/s, :func:`moving_record`), the same with 30 ms of rest,
   and the rest-first general quartic of issue 12; wrong model: the same moving record
   held to the forms that start at rest (the fit before issue 22), the moving record with
   a drive's 30 Hz ripple of 1 and 2 mrad on its line, and a clamp that oscillates;
3. the KES fits, right law: the bundled FB1 quartic and FB2 tagawa2003 loop, fresh noise
   each seed; another law: the frictional couple on that loop.

The motion fit's wrong-model evidence comes from its own test: a clamp speed 25 % low
leaves 2.0× (tests/test_calibration_path.py), θ(t) from the pre-issue-22 clamp fit 3.0×.

    python benchmarks/verdict_threshold.py [--seeds 20]
"""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

import numpy as np

from warpcloth.calibrate.clamp_fit import FORMS, fit_clamp_motion
from warpcloth.calibrate.noise import POOR_FIT_FACTOR, difference_noise

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scenes" / "data"))

BREAK_S, LINE_RAD_PER_S, A_RAD_PER_S2 = 0.045, 2.0, 2000.0
"""The record moving from its first sample (issue 22): θ = a t² + b t³ + c t⁴, with b and c
such that the quartic meets the 2 rad/s line at 45 ms with its speed and acceleration."""
QUARTIC = (2.0, 30.0, 900.0, 2e4)  # issue 12's general start (a1 … a4), break at 50 ms


def moving_coefficients() -> tuple[float, float, float]:
    """a, b, c of the moving record's quartic (rad/s^k)."""
    t1 = BREAK_S
    b, c = np.linalg.solve(
        [[3 * t1**2, 4 * t1**3], [6 * t1, 12 * t1**2]], [LINE_RAD_PER_S - 2 * A_RAD_PER_S2 * t1, -2 * A_RAD_PER_S2]
    )
    return A_RAD_PER_S2, float(b), float(c)


def moving_record(t: np.ndarray) -> np.ndarray:
    """The moving record's θ(t) from t = 0 (0 before it)."""
    a, b, c = moving_coefficients()
    tau = np.clip(t, 0, BREAK_S)
    return a * tau**2 + b * tau**3 + c * tau**4 + LINE_RAD_PER_S * np.clip(t - BREAK_S, 0, None)


def rest_first_record(t: np.ndarray) -> np.ndarray:
    """Issue 12's general quartic from t = 0 after rest, then its line (never stops)."""
    tau = np.clip(t, 0, 0.05)
    theta = sum(a * tau ** (k + 1) for k, a in enumerate(QUARTIC))
    speed = sum((k + 1) * a * 0.05**k for k, a in enumerate(QUARTIC))
    return theta + speed * np.clip(t - 0.05, 0, None)


def ripple(t: np.ndarray, amplitude: float) -> np.ndarray:
    """A drive's 30 Hz speed ripple on the line (rad): what no form of the clamp fit holds."""
    return amplitude * np.sin(2 * np.pi * 30 * np.clip(t - BREAK_S, 0, None))


def spread(ratios: list[float]) -> str:
    """min / median / max of a list of ratios."""
    r = np.asarray(ratios)
    return f"{r.min():.3f} / {np.median(r):.3f} / {r.max():.3f}"


def clamp_ratios(record: np.ndarray, t: np.ndarray, seeds: int, forms: tuple[str, ...] = tuple(FORMS)) -> list[float]:
    """RMS / estimated noise of the clamp fit over noise seeds (σ = 1 mrad)."""
    out = []
    for seed in range(seeds):
        fit = fit_clamp_motion(t, record + np.random.default_rng(seed).normal(0, 1e-3, len(t)), forms)
        out.append(fit.rms_rad / fit.noise_rad)
    return out


def kes_ratios(seeds: int) -> dict[str, list[float]]:
    """RMS / noise of the tensile quartic and two bending laws on the bundled loops, fresh noise."""
    import tempfile

    import make_kes_examples as kes_data

    from warpcloth.calibrate.kes import (
        fit_bending,
        fit_frictional_couple,
        fit_tensile,
        read_bending_csv,
        read_tensile_csv,
    )

    tensile = kes_data.tensile_example()
    tensile[:, 1] -= np.random.default_rng(2026).normal(0.0, kes_data.TENSILE_NOISE_GF_PER_CM, len(tensile))
    bending = kes_data.bending_example()
    bending[:, 1] -= np.random.default_rng(2027).normal(0.0, kes_data.BENDING_NOISE_GF_CM_PER_CM, len(bending))
    out: dict[str, list[float]] = {"tensile quartic": [], "tagawa2003 (right law)": [], "frictional_couple": []}

    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(seeds):
            rng = np.random.default_rng(100 + seed)
            t = tensile.copy()
            t[:, 1] += rng.normal(0.0, kes_data.TENSILE_NOISE_GF_PER_CM, len(t))
            b = bending.copy()
            b[:, 1] += rng.normal(0.0, kes_data.BENDING_NOISE_GF_CM_PER_CM, len(b))
            np.savetxt(Path(tmp) / "t.csv", t, delimiter=",", header="strain_percent,force_gf_per_cm", comments="")
            np.savetxt(
                Path(tmp) / "b.csv", b, delimiter=",", header="curvature_per_cm,moment_gf_cm_per_cm", comments=""
            )
            tl, bl = read_tensile_csv(Path(tmp) / "t.csv"), read_bending_csv(Path(tmp) / "b.csv")
            out["tensile quartic"].append(fit_tensile(tl).rms_gf_per_cm / difference_noise([tl.force]))
            noise = difference_noise([bl.moment])
            out["tagawa2003 (right law)"].append(fit_bending(bl).rms_gf_cm_per_cm / noise)
            out["frictional_couple"].append(fit_frictional_couple(bl).rms_gf_cm_per_cm / noise)
    return out


def main() -> None:
    """Print the table of RMS / noise spreads (min / median / max over seeds)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    args = parser.parse_args()
    print(
        f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}; "
        f"threshold POOR_FIT_FACTOR = {POOR_FIT_FACTOR}; {args.seeds} seeds; min / median / max of RMS / noise"
    )
    for n in (60, 100, 200, 500):
        ratios = np.array(
            [
                float(np.sqrt(np.mean(x**2))) / difference_noise([x])
                for x in (np.random.default_rng(seed).normal(0, 1.0, n) for seed in range(5000))
            ]
        )
        print(
            f"white noise alone, n = {n} (5000 seeds): sd {ratios.std():.3f}, max {ratios.max():.3f}, "
            f"share above {POOR_FIT_FACTOR}: {np.mean(ratios > POOR_FIT_FACTOR):.4f}, above 1.3: "
            f"{np.mean(ratios > 1.3):.4f}"
        )
    t = np.round(np.arange(0.0, 0.2, 1e-3), 6)
    t30 = np.round(np.arange(-0.03, 0.2, 1e-3), 6)
    t12 = np.round(np.arange(-0.02, 0.2, 1e-3), 6)
    at_rest = tuple(f for f, (_, _, rest_first) in FORMS.items() if rest_first)
    rows = {
        "clamp, moving from the first sample (right)": clamp_ratios(moving_record(t), t, args.seeds),
        "clamp, the same after 30 ms of rest (right)": clamp_ratios(moving_record(t30), t30, args.seeds),
        "clamp, issue 12's rest-first quartic (right)": clamp_ratios(rest_first_record(t12), t12, args.seeds),
        "clamp, moving record, rest-first forms only (wrong)": clamp_ratios(moving_record(t), t, args.seeds, at_rest),
        "clamp, moving record + a 30 Hz ripple of 1 mrad (wrong)": clamp_ratios(
            moving_record(t) + ripple(t, 1e-3), t, args.seeds
        ),
        "clamp, moving record + a 30 Hz ripple of 2 mrad (wrong)": clamp_ratios(
            moving_record(t) + ripple(t, 2e-3), t, args.seeds
        ),
        "clamp, an oscillating clamp 0.3 sin(100 t) (wrong)": clamp_ratios(
            0.3 * np.sin(100 * np.clip(t12, 0, None)), t12, min(args.seeds, 5)
        ),
    }
    rows |= {f"KES, {name}": r for name, r in kes_ratios(args.seeds).items()}
    for name, ratios in rows.items():
        print(f"{name}: {spread(ratios)}")


if __name__ == "__main__":
    main()
