"""Measurements on recorded signals: the one ruler for simulation and experiment.

:func:`swing_summary` is *the* definition of a swing's first period, amplitudes and
decrements, used alike by ``warpcloth run``'s summary, the sweep summary and
``warpcloth analyse`` (on a measured trace or a run), so lab and simulation are measured
the same way: turning points of the laser-line displacement (the tip's where the strip
misses the line), the first period from turning point 0 to 2. :func:`first_period`
(between level crossings) is the instrument of the small-amplitude analytic tests.

**Turning points** (:func:`turning_points`). Each extreme is found on the samples (the
signal moves back from it by a prominence), then refined by least squares over the
samples within ±w of it, w = √(2f)/π × the local half-period, f = :data:`TURNING_WINDOW`
= 0.05: on a sinusoid, the samples within 5 % of the half-swing of the extreme, ±5 % of
the period (±8 samples at 300 Hz for a 0.52 s swing; at least 3). The fit is done about
the extreme sample, then again about its vertex, so the window is symmetric. The model
is x ≈ c + b s + a g(s), g(s) = s² − ⅔ λ s³ − (ω²/12) s⁴, the expansion of a damped
cosine about its turning point, with ω = π / half-period and λ the envelope's decay rate
from the two half-swings beside it (both from the coarse extremes, so the model stays
linear in c, b, a); the turning time is the vertex −b/2a, its value c + b s + a g(s)
there. The cubic term removes the bias a plain parabola over such a window has on a
decaying swing (λw²/5: 2.8e-4 of the period at ζ = 0.08), the quartic the cosine's
flattening of the values (2e-5 of the amplitude, 1e-4 of a small decrement). Given the
noise σ, the vertex time's standard uncertainty is propagated from the fit's covariance
σ²(DᵀD)⁻¹, and a turning point needs a move back of :data:`NOISE_PROMINENCE` σ too.

Why a window and not the parabola through the three samples around each extreme (the
rule before): on noisy data three samples are a confident wrong number. At 300 Hz with
0.2 mm noise on a 50 mm, 0.52 s swing their turning times scatter 4 ms (0.5 ms with the
window), and the bundled ``damped_swing_laser`` read 0.5135 s against 0.5203 s from the
noise-free run it was made from. The window is a fraction of the period, not a number
of samples, so the ruler reads the same at any sampling rate: that noise-free run gives
0.51915 s at 600 Hz and 0.51916 s at 300 Hz (three samples: 0.52032 and 0.52012 s; the
simulated laser line carries higher-mode ripple of tens of µm at its turning points,
which three samples follow and the window averages; hence simulated first periods moved
by up to 1 ms and amplitudes by up to −0.1 % with this rule). Measured (the bounds are
tests/test_metrics.py's):

- damped cosine, noise-free, 300 and 600 Hz, ζ = 0.005–0.08: period within 3.4e-6,
  amplitude and decrement within 6e-7 (relative);
- the same, 0.52 s, 50 mm, ζ = 0.02, σ = 0.2 mm, 400 seeds: period bias +0.02 ms,
  scatter 0.50 ms at 300 Hz (stated 0.54 ms), +0.03 and 0.36 ms at 600 Hz (stated
  0.37 ms); first amplitude unbiased (≤ 7 µm), scatter 0.1 mm (the release sample's
  noise). Three samples: 4.2 ms and 19 ms (at 600 Hz noise made false turning points),
  amplitudes 0.09–0.14 mm too large (the noisy top);
- ``damped_swing_laser`` (noise estimated 0.193 mm): 0.52101 ± 0.00089 s against the
  truth's 0.51915 s (2.1 u, this draw; the truth run at 300 Hz over 400 noise seeds:
  bias +0.06 ms, scatter 0.86 ms, stated 0.81 ms).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from warpcloth.errors import ArgumentError

TIME_TOLERANCE_S = 1e-9
"""Sample times written with 10 digits still count as inside a comparison window."""


def crossing_times(t: np.ndarray, x: np.ndarray, level: float = 0.0) -> np.ndarray:
    """Times where ``x`` crosses ``level`` (either direction), linearly interpolated.

    Every crossing at once, in NumPy. SciPy's root finders (``brentq``) take one bracket
    per call, and the roots of the linear interpolant (``PPoly.roots`` of a ``k = 1``
    spline) also report a sample that touches the level without crossing it.
    """
    t = np.asarray(t, dtype=float)
    d = np.asarray(x, dtype=float) - level
    ok = np.isfinite(d)
    t, d = t[ok], d[ok]
    i = np.nonzero((d[:-1] * d[1:] < 0) | ((d[:-1] == 0) & (d[1:] != 0)))[0]
    return t[i] - d[i] * (t[i + 1] - t[i]) / (d[i + 1] - d[i])


def first_period(t: np.ndarray, x: np.ndarray, level: float | None = None) -> float:
    """First full period of an oscillation about ``level`` (default: the signal's mean).

    Measured between the first and third crossings, so a start at rest or in motion
    gives the same answer; NaN if the signal crosses fewer than three times. This is not
    the first period ``warpcloth run``, sweeps and ``analyse`` report (:func:`swing_metrics`:
    turning points 0 to 2, from the release): on a decaying swing the two time different
    stretches and differ (the bundled swing at γ = 0.5 /s: 0.5052 s here, 0.5165 s there).
    """
    x = np.asarray(x, dtype=float)
    if level is None:
        level = float(np.nanmean(x))
    c = crossing_times(t, x, level)
    return float(c[2] - c[0]) if len(c) >= 3 else float("nan")


RESOLUTION_M = 1e-9
"""Swings smaller than this (m) are rounding, not motion: a strip at rest has none."""

TURNING_WINDOW = 0.05
"""Each turning point is fitted over the samples within this fraction of the half-swing
of it on a sinusoid of the local half-period: ±√(2·0.05)/(2π) = ±5 % of the period."""

NOISE_PROMINENCE = 8.0
"""With a noise σ given, a turning point needs a move back by this many σ (two samples
of a flat top differ by 8 σ with probability 1.5e-8)."""


class TurningPoints(NamedTuple):
    """Alternating turning points of an oscillation (see :func:`turning_points`)."""

    times: np.ndarray
    """Times of the turning points (s)."""
    values: np.ndarray
    """Signal at the turning points."""
    time_u: np.ndarray
    """Standard uncertainty of each time from the noise (0 at an unrefined sample, NaN with no noise given)."""


def turning_points(
    t: np.ndarray,
    x: np.ndarray,
    starts_at_rest: bool = False,
    prominence: float = 0.01,
    resolution: float = RESOLUTION_M,
    noise: float | None = None,
) -> TurningPoints:
    """Alternating turning points of an oscillation, least-squares refined (module docstring).

    A turning point counts once the signal has moved back from it by more than
    ``prominence`` × the signal's range (and, with ``noise`` σ given, by more than
    :data:`NOISE_PROMINENCE` σ), so ripples of higher modes near a turning point and
    sampling noise are not taken for half-cycles, and the search ends by itself once the
    swing has decayed below that. The last, unconfirmed extreme of the record is not
    reported, nor anything in a signal whose range is below ``resolution``. With
    ``starts_at_rest`` (a release) the first sample is a turning point, taken as is. With
    ``noise`` (σ of white noise on ``x``), ``time_u`` is each time's standard uncertainty.

    Why not :func:`scipy.signal.find_peaks`: its prominence is a peak's height above the
    higher of its two bases over the whole record, not the move back since the last
    turning point, so it neither makes maxima and minima alternate nor leaves out the
    last, unconfirmed extreme, and it never reports the release sample; the refinement
    is a linear least-squares fit (NumPy's ``lstsq``), where SciPy adds nothing.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    ok = np.isfinite(x)
    t, x = t[ok], x[ok]
    if len(x) < 3 or np.ptp(x) <= resolution:
        return TurningPoints(np.zeros(0), np.zeros(0), np.zeros(0))
    threshold = max(prominence * np.ptp(x), NOISE_PROMINENCE * (noise or 0.0))
    found = [0] if starts_at_rest else []
    high = low = 0  # indices of the running maximum and minimum since the last turning point
    rising = None  # direction of travel, unknown until the first confirmed move
    for k in range(1, len(x)):
        if x[k] > x[high]:
            high = k
        if x[k] < x[low]:
            low = k
        if rising is not False and x[k] < x[high] - threshold:
            if rising:
                found.append(high)
            rising, low = False, k
        elif rising is not True and x[k] > x[low] + threshold:
            if rising is False:
                found.append(low)
            rising, high = True, k
    coarse_t, coarse_x = t[found], x[found]
    refined = np.array(
        [
            _refine(t, x, j, *_local_swing(coarse_t, coarse_x, k), noise) if 0 < j < len(x) - 1 else (t[j], x[j], 0.0)
            for k, j in enumerate(found)
        ],
        dtype=float,
    ).reshape(-1, 3)
    return TurningPoints(*refined.T)


def _local_swing(times: np.ndarray, values: np.ndarray, k: int) -> tuple[float, float]:
    """Half-period and envelope decay rate (1/s) about coarse turning point ``k``, from the
    two half-swings beside it (the last two at the record's end); no decay with only one
    half-swing, (0, 0) for a lone turning point."""
    if len(times) < 2:
        return 0.0, 0.0
    if len(times) == 2:
        return float(abs(times[1] - times[0])), 0.0
    i = min(max(k - 1, 0), len(times) - 3)
    half_period = float(times[i + 2] - times[i]) / 2
    before, after = abs(values[i + 1] - values[i]), abs(values[i + 2] - values[i + 1])
    return half_period, float(np.log(before / after) / half_period) if before > 0 and after > 0 else 0.0


def _refine(
    t: np.ndarray, x: np.ndarray, j: int, half_period: float, decay: float, noise: float | None
) -> tuple[float, float, float]:
    """Time, value and time uncertainty of the turning point near sample ``j``: the vertex
    of x ≈ c + b s + a g(s) fitted by least squares over |s| ≤ w (module docstring), first
    about sample ``j``, then about that vertex."""
    half_width = np.sqrt(2 * TURNING_WINDOW) / np.pi * half_period
    omega = np.pi / half_period if half_period > 0 else 0.0

    def shape(s: np.ndarray | float) -> np.ndarray | float:
        return s**2 - (2 * decay / 3) * s**3 - (omega**2 / 12) * s**4

    centre = t[j]
    for _ in range(2):
        s = t - centre
        window = np.nonzero(np.abs(s) <= half_width)[0]
        if len(window) < 3:
            window = np.sort(np.argsort(np.abs(s), kind="stable")[:3])
        s = s[window]
        design = np.stack([np.ones_like(s), s, shape(s)], axis=1)
        (c, b, a), *_ = np.linalg.lstsq(design, x[window], rcond=None)
        vertex = float(np.clip(-b / (2 * a), s[0], s[-1])) if a != 0 else 0.0
        centre = centre + vertex
    value = c + b * vertex + a * shape(vertex)
    if noise is None or a == 0:
        return centre, value, float("nan")
    gradient = np.array([0.0, -1 / (2 * a), b / (2 * a**2)])  # of the vertex -b / 2a with respect to (c, b, a)
    return centre, value, float(noise * np.sqrt(gradient @ np.linalg.solve(design.T @ design, gradient)))


def extrema(
    t: np.ndarray,
    x: np.ndarray,
    starts_at_rest: bool = False,
    prominence: float = 0.01,
    resolution: float = RESOLUTION_M,
) -> tuple[np.ndarray, np.ndarray]:
    """Times and values of :func:`turning_points`."""
    points = turning_points(t, x, starts_at_rest, prominence, resolution)
    return points.times, points.values


def swing_summary(
    t: np.ndarray,
    laser: np.ndarray,
    tip: np.ndarray | None = None,
    starts_at_rest: bool = True,
    noise: float | None = None,
) -> dict:
    """:func:`swing_metrics` of the laser-line displacement, or of ``tip`` when the strip
    misses the laser line in more than a tenth of the samples; ``"signal"`` says which."""
    laser = np.asarray(laser, dtype=float)
    lengths = {"t": len(np.asarray(t)), "laser": len(laser)} | ({} if tip is None else {"tip": len(np.asarray(tip))})
    if len(set(lengths.values())) > 1:
        raise ArgumentError("laser", f"t, laser and tip must be one sample each per time; their lengths are {lengths}")
    use_laser = tip is None or np.isfinite(laser).sum() > 0.9 * len(laser)
    metrics = swing_metrics(t, laser if use_laser or tip is None else tip, starts_at_rest, noise)
    return {"signal": "laser_x" if use_laser else "tip_x"} | metrics


def swing_metrics(t: np.ndarray, signal: np.ndarray, starts_at_rest: bool = True, noise: float | None = None) -> dict:
    """Summary of a decaying swing: first period, half-cycle amplitudes, log decrements.

    ``half_cycle_amplitude[i]`` is half the swing between turning points i and i+1;
    ``log_decrement[i]`` = ln(A_i / A_{i+1}) per half-cycle; the first period is the
    time from the first turning point (the release, when the swing starts at rest) to
    the third, which needs no estimate of the centre line. With ``noise`` (σ of white
    noise on ``signal``) the summary also holds ``first_period_u_s``, the period's
    standard uncertainty.
    """
    times, values, time_u = turning_points(t, signal, starts_at_rest, noise=noise)
    amplitude = np.abs(np.diff(values)) / 2
    decrement = np.log(amplitude[:-1] / amplitude[1:]) if len(amplitude) > 1 else np.zeros(0)
    period = float(times[2] - times[0]) if len(times) >= 3 else float("nan")
    uncertainty = (
        {}
        if noise is None
        else {"first_period_u_s": float(np.hypot(time_u[0], time_u[2])) if len(times) >= 3 else float("nan")}
    )
    return {
        "first_period_s": period,
        **uncertainty,
        "first_amplitude_m": float(amplitude[0]) if len(amplitude) else float("nan"),
        "mean_log_decrement": float(decrement.mean()) if len(decrement) else float("nan"),
        "n_half_cycles": int(len(amplitude)),
        "half_cycle_amplitude_m": amplitude.tolist(),
        "log_decrement": decrement.tolist(),
    }


def comparison_window(
    spans: dict[str, tuple[float, float]], t_from: float | None = None, t_to: float | None = None
) -> tuple[float, float]:
    """The window (s) on which records of these ``spans`` (name → first, last sample time)
    are compared: ``--from``/``--to`` where given, else the overlap of every record. A
    window that reaches outside any record, or is empty, is an :class:`ArgumentError`
    naming the option and its value."""
    start_name = max(spans, key=lambda name: spans[name][0])
    end_name = min(spans, key=lambda name: spans[name][1])
    start, end = spans[start_name][0], spans[end_name][1]
    if t_from is not None and t_from < start - TIME_TOLERANCE_S:
        raise ArgumentError(
            "t_from",
            f"{t_from:g} s is before the start of {start_name} ({start:g} s): the window "
            "must lie inside every record compared",
        )
    if t_to is not None and t_to > end + TIME_TOLERANCE_S:
        raise ArgumentError(
            "t_to",
            f"{t_to:g} s is after the end of {end_name} ({end:g} s): the window must lie inside every record compared",
        )
    lower = start if t_from is None else t_from
    upper = end if t_to is None else t_to
    if not lower < upper:
        if t_from is not None:
            raise ArgumentError(
                "t_from",
                f"{t_from:g} s is not before the window's end {upper:g} s "
                + ("(--to)" if t_to is not None else f"(the end of {end_name})"),
            )
        if t_to is not None:
            raise ArgumentError(
                "t_to", f"{t_to:g} s is not after the window's start {lower:g} s (the start of {start_name})"
            )
        raise ArgumentError(
            "spans",
            f"the records do not overlap in time: {end_name} ends at {end:g} s, before "
            f"{start_name} starts at {start:g} s",
        )
    return float(lower), float(upper)


def _peak_abs(series: np.ndarray) -> float:
    # NaN for an empty record (a sheet that diverged while settling, before t = 0)
    return float(np.nanmax(np.abs(series))) if np.isfinite(series).any() else float("nan")


def sheet_metrics(
    markers: np.ndarray,
    clamp_displacement: np.ndarray,
    direction: tuple[float, float, float],
    probes: dict[str, np.ndarray],
    energy_total: np.ndarray,
) -> dict[str, float]:
    """What a sheet's record says in numbers, measured from t = 0 (its first sample): the
    one definition ``warpcloth run``'s sheet summary and a sheet sweep's summary share.

    ``markers`` ``[sample, marker, xyz]`` (m), ``clamp_displacement`` the clamp's
    translation along ``direction`` ``[sample]`` (m), ``probes`` the sheet's probe series
    by name (``cell_shear_angle`` and the works, SI), ``energy_total`` the budget that
    should stay constant (:meth:`~warpcloth.sheet.SheetResult.energy_total`). Per marker ``k``:
    ``marker_k_peak_displacement_mm`` (the largest distance from its t = 0 position),
    ``marker_k_peak_z_mm`` (sideways), ``marker_k_peak_x_mm`` (out of the plane) and
    ``marker_k_peak_z_against_clamp_mm`` (sideways less the clamp's own translation: the
    swing itself); the probed cell's ``peak_shear_angle_deg`` (its largest absolute shear
    angle); the works done to the end against the laws' hysteresis (``hysteresis_work_J``, bending and shear), the
    air (``damping_work_J``) and by the clamp (``drive_work_J``); and the energy budget's
    largest drift from its t = 0 value, ``energy_drift_J``, also as a part of the largest
    work the clamp did, ``energy_drift_relative`` (NaN when the clamp did none)."""
    out: dict[str, float] = {}
    unit = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    clamp = clamp_displacement[:, None] * unit[None, :]
    for k in range(markers.shape[1]):
        moved = markers[:, k] - markers[0, k]
        out[f"marker_{k}_peak_displacement_mm"] = 1e3 * _peak_abs(np.linalg.norm(moved, axis=1))
        out[f"marker_{k}_peak_z_mm"] = 1e3 * _peak_abs(moved[:, 2])
        out[f"marker_{k}_peak_x_mm"] = 1e3 * _peak_abs(moved[:, 0])
        out[f"marker_{k}_peak_z_against_clamp_mm"] = 1e3 * _peak_abs(moved[:, 2] - clamp[:, 2])
    out["peak_shear_angle_deg"] = float(np.degrees(_peak_abs(probes["cell_shear_angle"])))
    for name in ("hysteresis_work", "damping_work", "drive_work"):
        series = probes[name]
        out[f"{name}_J"] = float(series[-1]) if len(series) else float("nan")
    drift = _peak_abs(energy_total - energy_total[0]) if len(energy_total) else float("nan")
    scale = _peak_abs(probes["drive_work"])
    out["energy_drift_J"] = drift
    out["energy_drift_relative"] = drift / scale if scale > 0 else float("nan")
    return out
