"""Measurements on recorded signals (periods, crossings) shared by tests and tools."""

from __future__ import annotations

from collections.abc import Callable

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


def hanging_beam_mode(gamma: float, mode: int = 0, n_basis: int = 24) -> tuple[float, Callable]:
    """λ and mode shape W(ξ) of the clamped hanging beam, W⁗ − γ((1−ξ)W′)′ = λ²W.

    ξ = s/L from the clamp, γ = ρ_A g L³ / B, λ² = ρ_A L⁴ ω² / B, so ω = λ √(B/(ρ_A L⁴)).
    Rayleigh–Ritz with the clamped basis ξ² P_k(2ξ − 1) (the free-end conditions are
    natural): an upper bound that converges fast for the low modes. γ = 0 gives the
    cantilever's 1.8751²; γ → ∞ approaches the heavy chain's λ² = 1.2024² γ. W is
    normalised to W(1) = 1.
    """
    from numpy.polynomial import legendre

    nodes, weights = legendre.leggauss(4 * n_basis)
    xi = (nodes + 1) / 2
    weights = weights / 2
    polys = [legendre.Legendre.basis(k, domain=[0, 1]) for k in range(n_basis)]
    basis, slope, bend = [], [], []
    for p in polys:
        # q = ξ² p with p a shifted Legendre polynomial, differentiated in that basis
        p0, p1, p2 = p(xi), p.deriv(1)(xi), p.deriv(2)(xi)
        basis.append(xi**2 * p0)
        slope.append(2 * xi * p0 + xi**2 * p1)
        bend.append(2 * p0 + 4 * xi * p1 + xi**2 * p2)
    basis, slope, bend = np.array(basis), np.array(slope), np.array(bend)
    stiffness = (bend * weights) @ bend.T + gamma * (slope * weights * (1 - xi)) @ slope.T
    mass = (basis * weights) @ basis.T
    inv = np.linalg.inv(np.linalg.cholesky(mass))
    values, vectors = np.linalg.eigh(inv @ stiffness @ inv.T)
    coefficients = inv.T @ vectors[:, mode]
    tip = sum(c * p(1.0) for c, p in zip(coefficients, polys, strict=True))

    def shape(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return sum(c * x**2 * p(x) for c, p in zip(coefficients, polys, strict=True)) / tip

    return float(np.sqrt(values[mode])), shape
