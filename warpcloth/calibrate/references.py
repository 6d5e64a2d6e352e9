"""Exact references nobody here invented, that the simulated strip is checked against."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


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
