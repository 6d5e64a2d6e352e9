"""Measurements on recorded signals (periods, crossings) shared by tests and tools."""

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


def extrema(t: np.ndarray, x: np.ndarray, starts_at_rest: bool = False,
            floor: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Alternating turning points (times, values) of an oscillation, parabola-refined.

    With ``starts_at_rest`` (a release) the first sample is a turning point. They stop
    once a half-cycle's amplitude falls below ``floor`` × the first one, where sampling
    noise and tensile ripple would otherwise add false ones.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    ok = np.isfinite(x)
    t, x = t[ok], x[ok]
    if len(x) < 3:
        return np.zeros(0), np.zeros(0)
    d = np.diff(x)
    i = np.nonzero(d[:-1] * d[1:] < 0)[0] + 1
    times, values = [], []
    if starts_at_rest:
        times.append(t[0])
        values.append(x[0])
    for j in i:
        a, b, c = x[j - 1], x[j], x[j + 1]
        curvature = a - 2 * b + c
        shift = 0.5 * (a - c) / curvature if curvature != 0 else 0.0
        times.append(t[j] + shift * (t[j + 1] - t[j]))
        values.append(b - 0.25 * (a - c) * shift)
    times, values = np.array(times), np.array(values)
    # keep alternation: of two same-direction turning points keep the more extreme
    keep_t, keep_v = list(times[:1]), list(values[:1])
    for tt, vv in zip(times[1:], values[1:], strict=True):
        if len(keep_v) >= 2 and (keep_v[-1] - keep_v[-2]) * (vv - keep_v[-1]) > 0:
            keep_t[-1], keep_v[-1] = tt, vv
        else:
            keep_t.append(tt)
            keep_v.append(vv)
    values = np.array(keep_v)
    amplitude = np.abs(np.diff(values)) / 2
    if len(amplitude):
        small = np.nonzero(amplitude < floor * amplitude[0])[0]
        if len(small):
            return np.array(keep_t[: small[0] + 1]), values[: small[0] + 1]
    return np.array(keep_t), values


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
