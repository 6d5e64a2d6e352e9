"""Explicit Euler updates of one free node and the stepping parameters the solver owns
(docs/model.md §9).

A scheme is a wp.func ``(x, v, f, m, dt) -> (x_new, v_new)`` of a node of either body;
the strip's and the sheet's kernels are generated per scheme, so the choice costs no
branch inside the substep loop, and a new scheme is one function here for both. ``imex``
updates nodes as semi-implicit Euler does, with the implicit tension of
:mod:`.implicit_stretching` added to the forces (:data:`IMPLICIT_STRETCHING`).
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from .types import precision

IMPLICIT_STRETCHING = ("imex", "imex_trapezoidal")
"""Schemes whose substep takes the segments' stretching implicitly (kernels/implicit_stretching.py)."""


@functools.cache
def build(scalar: Any, dim: int = 2) -> SimpleNamespace:
    """The strip's ``Stepping`` struct and the ``schemes`` (name → node update) for
    ``scalar`` and nodes of ``dim`` components (2: a strip's, 3: a sheet's): one node
    update serves every body."""
    types = precision(scalar)
    vec = types.vec2 if dim == 2 else types.vec3

    @wp.struct
    class Stepping:
        """How the solver steps: dt, its divergence limit, and the drive phases in steps."""

        dt: scalar
        max_strain: scalar  # |ε| beyond which a strip counts as diverged
        release_step: int  # step index of t = 0 (release); the hold lasts before it
        move_steps: int  # steps spent carrying the free end to the hold target

    @wp.func
    def kick_mass(m: scalar, starts: bool):
        # The mass a node's velocity kick divides by. Symplectic Euler carries velocities at
        # half steps, v_{n+1/2} = v_{n-1/2} + dt a_n. A node whose velocity is known at the
        # step itself (``starts``: at the run's first step, or freed from a constraint there)
        # takes half that kick, v_{n+1/2} = v_n + (dt/2) a_n; a full one offsets its whole
        # later motion by (dt/2) a_n, a first-order error (docs/model.md §9.1).
        if starts:
            return scalar(2.0) * m
        return m

    @wp.func
    def whole_kick_mass(m: scalar, starts: bool):
        # Forward Euler's velocities live at the steps themselves: every kick is whole.
        return m

    @wp.func
    def semi_implicit_euler(x: vec, v: vec, f: vec, m: scalar, dt: scalar):
        # Symplectic: the position moves with the updated velocity.
        v_new = v + f * (dt / m)
        return x + v_new * dt, v_new

    @wp.func
    def forward_euler(x: vec, v: vec, f: vec, m: scalar, dt: scalar):
        # The paper's eqs. 5-6: the position moves with the old velocity.
        v_new = v + f * (dt / m)
        return x + v * dt, v_new

    return SimpleNamespace(
        Stepping=Stepping,
        kick_mass={
            "semi_implicit": kick_mass,
            "forward": whole_kick_mass,
            "imex": kick_mass,
            "imex_trapezoidal": kick_mass,
        },
        schemes={
            "semi_implicit": semi_implicit_euler,
            "forward": forward_euler,
            "imex": semi_implicit_euler,
            "imex_trapezoidal": semi_implicit_euler,
        },
    )
