"""Exact references nobody here invented, that the simulated strip is checked against."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import brentq

from warpcloth.errors import ArgumentError


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


def heavy_elastica(
    kappa: float, steps: int = 4000, natural_curvature: float | Callable[[float], float] = 0.0
) -> dict[str, float]:
    """Static shape of an inextensible cantilever clamped horizontally under its own weight.

    θ(s), the tangent's angle below the horizontal at s = arc length / L, solves
    (θ′ + q)′ = −κ (1 − s) cos θ with θ(0) = 0 (built in) and θ′(1) + q(1) = 0 (no moment
    at the free end), κ = ρ_A g L³ / D; q(s) = K_rest L is the strip's natural curvature
    (counter-clockwise positive, so it lifts a strip pointing along +x; a constant or a
    function of s), whose moment D (K − K_rest) the equation balances. Without one it is
    θ″ = −κ (1 − s) cos θ. Shooting on the root moment φ(0) = θ′(0) + q(0), bracketed by
    [−κ/2, κ/2] (the weight's moment about the root is at most κ/2), solved by
    :func:`scipy.optimize.brentq` to rounding; RK4 in s (fixed steps: the convergence
    tests need the integrator's order known, which an adaptive ``solve_ivp`` would not state).
    Returns the tip's reach x/L and drop y/L (of ∫cos θ, ∫sin θ), the tip angle θ(1) in
    rad, and the root slope θ′(0).
    """
    ds = 1.0 / steps
    q = natural_curvature if callable(natural_curvature) else (lambda s, c=float(natural_curvature): c)

    def shoot(moment: float) -> tuple[float, float, float, float]:
        # (θ, φ = θ′ + q, x, y) from the root
        theta, phi, x, y = 0.0, moment, 0.0, 0.0

        def rhs(s: float, th: float, ph: float) -> tuple[float, float, float, float]:
            return ph - q(s), -kappa * (1.0 - s) * math.cos(th), math.cos(th), math.sin(th)

        for i in range(steps):
            s = i * ds
            k1 = rhs(s, theta, phi)
            k2 = rhs(s + ds / 2, theta + ds / 2 * k1[0], phi + ds / 2 * k1[1])
            k3 = rhs(s + ds / 2, theta + ds / 2 * k2[0], phi + ds / 2 * k2[1])
            k4 = rhs(s + ds, theta + ds * k3[0], phi + ds * k3[1])
            theta += ds / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            phi += ds / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            x += ds / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
            y += ds / 6 * (k1[3] + 2 * k2[3] + 2 * k3[3] + k4[3])
        return theta, phi, x, y

    moment = brentq(lambda m: shoot(m)[1], -0.5 * kappa, 0.5 * kappa, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    theta, _, x, y = shoot(moment)
    return {"tip_reach": x, "tip_drop": y, "tip_angle": theta, "root_slope": moment - q(0.0)}


def hanging_beam_eigenvalue(gamma: float, steps: int = 2000, lambda_max: float = 60.0) -> float:
    """λ of the first mode of W⁗ − γ((1−ξ)W′)′ = λ²W by shooting: a second reference,
    independent of :func:`hanging_beam_mode`'s Rayleigh–Ritz (:func:`two_section_beam_mode`
    with a uniform rigidity)."""
    return two_section_beam_mode(gamma, steps=steps, lambda_max=lambda_max)[0]


def two_section_beam_mode(
    gamma: float, root_length: float = 0.0, root_factor: float = 1.0, steps: int = 2000, lambda_max: float = 60.0
) -> tuple[float, Callable]:
    """λ and mode shape W(ξ) (W(1) = 1) of the first mode of the clamped hanging beam whose
    root section ξ < ``root_length`` is ``root_factor`` times as rigid as the rest:
    (d W″)″ − γ((1−ξ)W′)′ = λ²W with d = ``root_factor`` there and 1 beyond, by shooting.

    ξ = s/L, γ = ρ_A g L³ / D and λ² = ρ_A L⁴ ω² / D with the rigidity D of the outer
    section. In the moment M = d W″ and the shear Q = M′ − γ(1−ξ)W′ (continuous where d
    jumps) the equation is W′ = ·, W″ = M/d, M′ = Q + γ(1−ξ)W′, Q′ = λ²W. From the clamp
    (W = W′ = 0) two solutions start with (M, Q) = (1, 0) and (0, 1); the free end needs
    M(1) = Q(1) = 0, so λ is the first zero of their determinant at ξ = 1, bracketed on a
    grid of λ (all integrated at once, RK4 in ξ with the section boundary on a step) and
    solved inside the bracket by :func:`scipy.optimize.brentq`.
    """
    if not 0.0 <= root_length < 1.0:
        raise ArgumentError("root_length", f"must lie in [0, 1), got {root_length:g}")
    if not root_factor > 0:
        raise ArgumentError("root_factor", f"must be > 0, got {root_factor:g}")
    inner = round(steps * root_length)
    grid_xi = np.concatenate(
        [
            np.linspace(0.0, root_length, inner + 1)[:-1] if inner else np.zeros(0),
            np.linspace(root_length if inner else 0.0, 1.0, steps - inner + 1),
        ]
    )

    def integrate(lam: np.ndarray, keep: bool = False) -> np.ndarray:
        lam = np.atleast_1d(np.asarray(lam, dtype=float))
        y = np.zeros((len(lam), 4, 2))
        y[:, 2, 0] = 1.0
        y[:, 3, 1] = 1.0
        path = [y]

        def rhs(xi: float, y: np.ndarray, d: float) -> np.ndarray:
            w, w1, m, q = y[:, 0], y[:, 1], y[:, 2], y[:, 3]
            return np.stack([w1, m / d, q + gamma * (1.0 - xi) * w1, (lam**2)[:, None] * w], axis=1)

        for a, b in zip(grid_xi[:-1], grid_xi[1:], strict=True):
            d = root_factor if b <= root_length else 1.0
            dxi = b - a
            k1 = rhs(a, y, d)
            k2 = rhs(a + dxi / 2, y + dxi / 2 * k1, d)
            k3 = rhs(a + dxi / 2, y + dxi / 2 * k2, d)
            k4 = rhs(b, y + dxi * k3, d)
            y = y + dxi / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            if keep:
                path.append(y)
        return np.stack(path) if keep else y

    def determinant(lam: np.ndarray) -> np.ndarray:
        y = integrate(lam)
        return y[:, 2, 0] * y[:, 3, 1] - y[:, 2, 1] * y[:, 3, 0]

    grid = np.linspace(0.5, lambda_max, 48)  # the first sign change brackets the first mode
    values = determinant(grid)
    change = np.nonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0]
    if not len(change):
        raise ArgumentError("lambda_max", f"no eigenvalue below λ = {lambda_max:g} for γ = {gamma:g}")
    low, high = grid[change[0]], grid[change[0] + 1]
    lam = brentq(lambda lam: float(determinant(lam)[0]), low, high, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    path = integrate(lam, keep=True)[:, 0]  # [ξ, variable, solution]
    a, b = path[-1, 2, 1], -path[-1, 2, 0]  # the combination with no moment at the free end
    w = a * path[:, 0, 0] + b * path[:, 0, 1]

    def shape(x: np.ndarray) -> np.ndarray:
        return np.interp(x, grid_xi, w) / w[-1]

    return float(lam), shape
