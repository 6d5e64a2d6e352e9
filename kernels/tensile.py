"""Tensile law of a segment: force per width T(ε) of the KES-FB1 quartic (docs/model.md §3).

T(ε) = a1 ε + a2 ε² + a3 ε³ + a4 ε⁴ for ε ≥ 0, odd-extended so that compression is as
stiff as tension; its energy per width ∫ T dε and its tangent dT/dε.
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from .types import precision


@functools.cache
def build(scalar: Any) -> SimpleNamespace:
    """``force_per_width``, ``energy_per_width`` and ``stiffness_per_width`` for ``scalar``."""
    vec4 = precision(scalar).vec4
    half = scalar(0.5)
    # 1/3 divided here, in double precision: written inside a Warp function, 1.0 / 3.0 is
    # divided in float32 and would cost the a2 term 3e-8 of its value.
    third = scalar(1.0 / 3.0)

    @wp.func
    def force_per_width(strain: scalar, a: vec4):
        # Quartic fit of the KES-FB1 loading branch, odd-extended so compression is stiff.
        e = wp.abs(strain)
        t = e * (a[0] + e * (a[1] + e * (a[2] + e * a[3])))
        return wp.sign(strain) * t

    @wp.func
    def energy_per_width(strain: scalar, a: vec4):
        e = wp.abs(strain)
        return e * e * (half * a[0] + e * (third * a[1] + e * (scalar(0.25) * a[2] + e * scalar(0.2) * a[3])))

    @wp.func
    def stiffness_per_width(strain: scalar, a: vec4):
        # dT/dε, even in ε: what an implicit treatment of stretching linearises with.
        e = wp.abs(strain)
        return a[0] + e * (scalar(2.0) * a[1] + e * (scalar(3.0) * a[2] + e * scalar(4.0) * a[3]))

    return SimpleNamespace(
        force_per_width=force_per_width, energy_per_width=energy_per_width, stiffness_per_width=stiffness_per_width
    )
