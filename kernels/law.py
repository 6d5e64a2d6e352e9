"""What a bending law is, said once: :class:`BendingLaw`, the one description from which
everything else about a law is derived.

A law's file (``kernels/bending_<name>.py``) holds its Warp functions and ends with its
description, ``LAW``; :mod:`.laws` lists the descriptions. From a description warpcloth
derives the scene's [material] fields (their names, defaults, documentation and which law
reads them), the one KES → SI conversion, the fit aliases of ``warpcloth fit --free``,
figure labels, the ``bending_law`` choices of the command line, the per-strip dispatch in
the kernels (:func:`warpcloth.kernels.laws.build`, generated over the list with
``wp.static``) and the KES fitter ``material fit-kes --law`` uses.

The kernel contract. ``build(scalar)`` returns :class:`LawFunctions`, four ``wp.func``\\s on
the shared types of :func:`~warpcloth.kernels.types.precision` (``law_parameters``, the
packed per-strip vector with D in slot 0 and the law's own parameters after it;
``law_memory``, the packed per-hinge vector whose last slot is the curvature at the last
force evaluation; ``reversal_memory``, the per-hinge reversal points a law with
return-point memory keeps), with one signature per function so that any law can stand in
any branch of the dispatch:

- ``fresh_memory(curvature, p, history, hinge, strip) -> memory``: a hinge that has never bent;
- ``follow(curvature, memory, p, history, hinge, strip) -> memory``: the memory after the
  curvature moved to ``curvature`` (its last slot set to ``curvature``);
- ``tangent(curvature, memory, p, history, hinge, strip) -> dM/dK`` on the current branch;
- ``hysteretic_moment(curvature, memory, p) -> M − D K`` (what ``follow`` left in the memory
  is all it may read, so probes can evaluate it without the reversal points).

A law whose ``follow`` ends by multiplying its memory by one exponential may also give
that ``follow`` in two parts, so that the CPU's force pass takes the exponentials of
several hinges in one vector call (kernels/exp_lanes.py):

- ``follow_before_decay(curvature, memory, p, history, hinge, strip) -> (memory, x)``: the
  memory ``follow`` returns but for the factor e^x, and x;
- ``decay(memory, factor, p) -> memory``: that memory with the factor applied,

such that ``follow`` is ``decay(m, wp.exp(x), p)`` of ``(m, x) = follow_before_decay(…)``
(tests/test_exp_lanes.py checks it bitwise for every registered law); x ≤ 0 keeps the
factor in [0, 1]. A law that
gives neither is followed whole, with x = 0.

Only Warp and the standard library are imported here, so units are not: a parameter's
``kind`` says what it measures, and :mod:`warpcloth.units` (``BENDING_UNITS``,
``SHEAR_UNITS``) what that is in KES units and SI; the fitter is named by the import path
of a :class:`warpcloth.calibrate.kes.bending_fit.LawFitter`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from warpcloth.errors import ArgumentError


class LawRegistryError(ImportError):
    """A bending law's description (built in, or from an installed package's entry point)
    that cannot be used: the message names the law and what is wrong. The command line
    prints it as one line."""


@dataclass(frozen=True)
class LawParameter:
    """One parameter of a bending law, as the kernels, scene files, fits and figures see it."""

    name: str
    """The SI name, the key in :class:`warpcloth.strip.LawParameters` (``dahl_moment``)."""
    scene_field: str
    """The [material] field of a scene, in KES units (``dahl_moment_gf_cm_per_cm``)."""
    kind: str
    """What the parameter measures in the law's own variables (:data:`KINDS`): the same
    law describes bending (curvature K, moment per width M) and in-plane shear (shear
    angle φ, shear force per width), so the kind gives its unit and its conversion to SI
    in each (:data:`warpcloth.units.BENDING_UNITS`, :data:`warpcloth.units.SHEAR_UNITS`)."""
    alias: str
    """The short name ``warpcloth fit --free`` accepts (``Ms``)."""
    label: str
    """The symbol figures print (``M_s``)."""
    doc: str
    """One line for the scene reference (the law names are prefixed to it)."""
    default: float | Callable[[Mapping[str, Any]], float] | None
    """The scene field's default in KES units where the default material file does not give
    it: a number, or a function of the default material's values of the same law's
    parameters by SI name (``{"hysteresis_d1": …}``, in that mode's KES units), so a law's
    default can be the default material's own loop; None: the default material gives it."""
    gt: float | None = None
    """The scene field must be greater than this."""
    ge: float | None = None
    """The scene field must be at least this."""
    amplitude: bool = False
    """The size of the law's hysteresis (0 = elastic): ``warpcloth fit`` searches it from 0
    to 4× the scene's value by default."""


@dataclass(frozen=True)
class LawFunctions:
    """A law's Warp functions for one precision (the contract in the module docstring)."""

    fresh_memory: Any
    follow: Any
    hysteretic_moment: Any
    tangent: Any
    follow_before_decay: Any = None
    decay: Any = None


@dataclass(frozen=True)
class BendingLaw:
    """A bending law: its name, parameters, memory, kernels and fitter (module docstring)."""

    name: str
    """What ``material.bending_law`` says (``dahl``)."""
    summary: str
    """A few words for the scene reference and the command line's help."""
    parameters: tuple[LawParameter, ...]
    """The law's own parameters, after the bending rigidity D every law reads first."""
    pack: Callable[..., tuple[float, ...]]
    """The packed per-strip parameters (D first) from D and :attr:`parameters` in SI."""
    memory: tuple[str, ...]
    """What each slot of the per-hinge memory holds, the last curvature last."""
    build: Callable[[Any], LawFunctions]
    """The law's :class:`LawFunctions` for a Warp scalar type (cached by the law)."""
    fitter: str
    """``module:attribute`` of the law's KES-FB2 fitter."""
    mesh_independent: bool
    """Whether the law's answers converge as the mesh and the step are refined
    (return-point memory); a law without it gives fitted values that depend on h
    (docs/model.md §15.6)."""
    uses_reversal_memory: bool = False
    """Whether the law keeps reversal points in the shared ``reversal_memory`` (allocated,
    at the run's ``reversal_memory`` depth, only for a batch with such a law)."""
    loop_closure: str = ""
    """The parameter (SI name) at whose curvature the law's KES loop closes, if it has one;
    figures chart the loop there instead of on the standard KES cycle."""

    def parameter(self, name: str) -> LawParameter:
        """The parameter called ``name`` (its SI name); an ArgumentError lists the law's."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise ArgumentError(
            "name",
            f"the {self.name} law has no parameter {name!r}; it has {', '.join(q.name for q in self.parameters)}",
        )


KINDS = ("moment", "curvature", "inverse_curvature", "number")
"""A law parameter measures a moment per width (bending) or force per width (shear), a
curvature (bending) or angle (shear), their inverse, or a pure number."""

BENDING_RIGIDITY = LawParameter(
    name="bending_rigidity",
    scene_field="bending_rigidity_gf_cm2_per_cm",
    kind="rigidity",
    alias="D",
    label="B = D",
    doc="D, slope of the centre line M = D K (every law)",
    default=0.0,
    ge=0,
)
"""D, the slope of the centre line M = D K: every law's first parameter, slot 0 of the packed vector."""
