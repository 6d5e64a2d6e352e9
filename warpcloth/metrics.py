"""Measurements on recorded signals: the one ruler for simulation and experiment.

:func:`swing_summary` is *the* definition of a swing's first period, amplitudes and
decrements, used alike by ``warpcloth run``'s summary, the sweep summary and
``warpcloth analyse`` (on a measured trace or a run), so lab and simulation are measured
the same way: turning points of the laser-line displacement (the tip's where the strip
misses the line), the first period from turning point 0 to 2. :func:`first_period`
(between level crossings) is the instrument of the small-amplitude analytic tests.
"""

from __future__ import annotations

import numpy as np


def crossing_times(t: np.ndarray, x: np.ndarray, level: float = 0.0) -> np.ndarray:
    """Times where ``x`` crosses ``level`` (either direction), linearly interpolated."""
    t = np.asarray(t, dtype=float)
    d = np.asarray(x, dtype=float) - level
    ok = np.isfinite(d)
    t, d = t[ok], d[ok]
    i = np.nonzero((d[:-1] * d[1:] < 0) | ((d[:-1] == 0) & (d[1:] != 0)))[0]
    return t[i] - d[i] * (t[i + 1] - t[i]) / (d[i + 1] - d[i])


def first_period(t: np.ndarray, x: np.ndarray, level: float | None = None) -> float:
    """First full period of an oscillation about ``level`` (default: the signal's mean).

    Measured between the first and third crossings, so a start at rest or in motion
    gives the same answer; NaN if the signal crosses fewer than three times.
    """
    x = np.asarray(x, dtype=float)
    if level is None:
        level = float(np.nanmean(x))
    c = crossing_times(t, x, level)
    return float(c[2] - c[0]) if len(c) >= 3 else float("nan")


RESOLUTION_M = 1e-9
"""Swings smaller than this (m) are rounding, not motion: a strip at rest has none."""


def extrema(t: np.ndarray, x: np.ndarray, starts_at_rest: bool = False,
            prominence: float = 0.01, resolution: float = RESOLUTION_M) -> tuple[np.ndarray, np.ndarray]:
    """Alternating turning points (times, values) of an oscillation, parabola-refined.

    A turning point counts once the signal has moved back from it by more than
    ``prominence`` × the signal's range, so ripples of higher modes near a turning point
    (and sampling noise) are not taken for half-cycles, and the search ends by itself
    once the swing has decayed below that. The last, unconfirmed extreme of the record
    is not reported, nor anything in a signal whose range is below ``resolution``.
    With ``starts_at_rest`` (a release) the first sample is a turning
    point.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    ok = np.isfinite(x)
    t, x = t[ok], x[ok]
    if len(x) < 3 or np.ptp(x) <= resolution:
        return np.zeros(0), np.zeros(0)
    threshold = prominence * np.ptp(x)
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
    times, values = [], []
    for j in found:
        if 0 < j < len(x) - 1:
            a, b, c = x[j - 1], x[j], x[j + 1]
            curvature = a - 2 * b + c
            shift = 0.5 * (a - c) / curvature if curvature != 0 else 0.0
            times.append(t[j] + shift * (t[j + 1] - t[j]))
            values.append(b - 0.25 * (a - c) * shift)
        else:
            times.append(t[j])
            values.append(x[j])
    return np.array(times), np.array(values)


def swing_summary(t: np.ndarray, laser: np.ndarray, tip: np.ndarray | None = None,
                  starts_at_rest: bool = True) -> dict:
    """:func:`swing_metrics` of the laser-line displacement, or of ``tip`` when the strip
    misses the laser line in more than a tenth of the samples; ``"signal"`` says which."""
    laser = np.asarray(laser, dtype=float)
    use_laser = tip is None or np.isfinite(laser).sum() > 0.9 * len(laser)
    metrics = swing_metrics(t, laser if use_laser else tip, starts_at_rest)
    return {"signal": "laser_x" if use_laser else "tip_x"} | metrics


def swing_metrics(t: np.ndarray, signal: np.ndarray, starts_at_rest: bool = True) -> dict:
    """Summary of a decaying swing: first period, half-cycle amplitudes, log decrements.

    ``half_cycle_amplitude[i]`` is half the swing between turning points i and i+1;
    ``log_decrement[i]`` = ln(A_i / A_{i+1}) per half-cycle; the first period is the
    time from the first turning point (the release, when the swing starts at rest) to
    the third, which needs no estimate of the centre line.
    """
    times, values = extrema(t, signal, starts_at_rest)
    amplitude = np.abs(np.diff(values)) / 2
    decrement = np.log(amplitude[:-1] / amplitude[1:]) if len(amplitude) > 1 else np.zeros(0)
    period = float(times[2] - times[0]) if len(times) >= 3 else float("nan")
    return {
        "first_period_s": period,
        "first_amplitude_m": float(amplitude[0]) if len(amplitude) else float("nan"),
        "mean_log_decrement": float(decrement.mean()) if len(decrement) else float("nan"),
        "n_half_cycles": int(len(amplitude)),
        "half_cycle_amplitude_m": amplitude.tolist(),
        "log_decrement": decrement.tolist(),
    }
