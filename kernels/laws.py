"""The bending laws a strip can use, and the one set of Warp functions that serves them
all, so strips of different laws run in the same batch and launch.

Each law is one file, ``bending_<name>.py``, ending with its description ``LAW``
(:class:`~warpcloth.kernels.law.BendingLaw`: parameters, memory, kernels, fitter; the
kernel contract is in kernels/law.py). :data:`LAWS` lists the descriptions: the four
built in, then any a separately installed package registers under the entry-point group
:data:`ENTRY_POINT_GROUP` (its value ``module:attribute`` naming a ``BendingLaw``). Adding
a law: its kernel file, its KES fitter, and one entry (here, or an entry point).

The packed parameters carry the law's index in :data:`LAWS` in their last slot; the
functions here dispatch on it per strip, one branch per law generated with ``wp.static``
over the list (one branch per hinge evaluation, uniform across a GPU warp when a batch is
sorted by law).
"""

import functools
from dataclasses import dataclass, replace
from importlib.metadata import entry_points
from types import SimpleNamespace
from typing import Any

import warp as wp

from warpcloth.errors import ArgumentError, InternalError

from . import bending_dahl, bending_frictional_couple, bending_masing, bending_masing_growing, bending_tagawa2003
from .law import BENDING_RIGIDITY, KINDS, BendingLaw, LawFunctions, LawParameter, LawRegistryError
from .types import LAST_CURVATURE_SLOT, LAW_MEMORY_SLOTS, LAW_PARAMETER_SLOTS, precision

ENTRY_POINT_GROUP = "warpcloth.bending_laws"
"""Where an installed package registers a bending law of its own."""

BUILT_IN = (
    bending_tagawa2003.LAW,
    bending_dahl.LAW,
    bending_frictional_couple.LAW,
    bending_masing.LAW,
    bending_masing_growing.LAW,
)
"""The laws warpcloth ships, in the order of their index in the packed parameters."""

LAW_SLOT = LAW_PARAMETER_SLOTS - 1
"""Where the packed parameters hold the law's index."""

DEFAULT_BENDING_LAW = bending_tagawa2003.LAW.name


def _registered() -> tuple[BendingLaw, ...]:
    laws = []
    for point in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda p: p.name):
        try:
            law = point.load()
        except Exception as exc:  # a broken plugin must name itself, not break every command anonymously
            raise LawRegistryError(
                f"the bending law {point.name!r} registered under {ENTRY_POINT_GROUP} as "
                f"{point.value!r} cannot be loaded: {exc}"
            ) from exc
        if not isinstance(law, BendingLaw):
            raise LawRegistryError(
                f"the bending law {point.name!r} registered under {ENTRY_POINT_GROUP} as "
                f"{point.value!r} is a {type(law).__name__}, not a warpcloth.kernels.law.BendingLaw"
            )
        laws.append(law)
    return tuple(laws)


def checked_laws(laws: tuple[BendingLaw, ...]) -> tuple[BendingLaw, ...]:
    """``laws`` if their descriptions fit together (unique names, aliases and scene fields, a
    parameter shared between laws described by one object, every kind known, the packed
    vector and the memory within the shared slots); else a LawRegistryError naming the law
    and what clashes."""
    names: set[str] = set()
    by_field: dict[str, LawParameter] = {BENDING_RIGIDITY.scene_field: BENDING_RIGIDITY}
    by_alias: dict[str, LawParameter] = {BENDING_RIGIDITY.alias: BENDING_RIGIDITY}
    for law in laws:
        if law.name in names:
            raise LawRegistryError(f"two bending laws are called {law.name!r}")
        names.add(law.name)
        if 1 + len(law.parameters) > LAW_SLOT:
            raise LawRegistryError(
                f"the {law.name} law has {len(law.parameters)} parameters after D; the packed "
                f"vector holds {LAW_SLOT - 1}"
            )
        own = [p.name for p in law.parameters]
        if len(set(own)) != len(own) or BENDING_RIGIDITY.name in own:
            raise LawRegistryError(
                f"the {law.name} law's parameters {', '.join(own)} repeat a name (D is every "
                "law's first parameter already)"
            )
        unknown = [p.name for p in law.parameters if p.kind not in KINDS]
        if unknown:
            raise LawRegistryError(
                f"the {law.name} law's parameter {unknown[0]!r} has kind "
                f"{law.parameter(unknown[0]).kind!r}; a kind is one of {', '.join(KINDS)}"
            )
        if len(law.memory) != LAW_MEMORY_SLOTS:
            raise LawRegistryError(
                f"the {law.name} law's memory has {len(law.memory)} slots; every law has "
                f"{LAW_MEMORY_SLOTS}, the last curvature last"
            )
        for p in law.parameters:
            for key, seen in ((p.scene_field, by_field), (p.alias, by_alias)):
                other = seen.setdefault(key, p)
                if other is not p:
                    raise LawRegistryError(
                        f"the {law.name} law's parameter {p.name!r} takes {key!r}, which another "
                        "parameter has (a parameter two laws share is one LawParameter)"
                    )
    return laws


LAWS: tuple[BendingLaw, ...] = checked_laws(BUILT_IN + _registered())
"""Every bending law, by its index in the packed parameters."""

BENDING_LAWS: dict[str, BendingLaw] = {law.name: law for law in LAWS}


def _parameters_by_field() -> dict[str, tuple[LawParameter, tuple[str, ...]]]:
    out: dict[str, tuple[LawParameter, tuple[str, ...]]] = {}
    for law in LAWS:
        for p in law.parameters:
            out[p.scene_field] = (p, out.get(p.scene_field, (p, ()))[1] + (law.name,))
    return out


LAW_PARAMETERS = _parameters_by_field()
"""Every law's own parameters by scene field (in the laws' order), each with the laws that
read it; D, which every law reads, is not among them (:data:`~warpcloth.kernels.law.BENDING_RIGIDITY`)."""

wp.set_module_options({"enable_backward": False})


def bending_law(name: str) -> BendingLaw:
    """The description of the bending law ``name``; an ArgumentError lists the known ones."""
    if name not in BENDING_LAWS:
        raise ArgumentError("bending_law", f"unknown bending law {name!r}; known: {', '.join(BENDING_LAWS)}")
    return BENDING_LAWS[name]


def packed_parameters(name: str, values: dict[str, float]) -> tuple[float, ...]:
    """The shared per-strip parameter vector of law ``name`` from D and its parameters in SI
    (by SI name): the law's own layout, zeros, then the law's index."""
    law = bending_law(name)
    own = tuple(float(v) for v in law.pack(values[BENDING_RIGIDITY.name], *(values[p.name] for p in law.parameters)))
    if len(own) > LAW_SLOT:
        raise InternalError(f"the {name} law packs {len(own)} parameters; the shared vector holds {LAW_SLOT}")
    return own + (0.0,) * (LAW_SLOT - len(own)) + (float(LAWS.index(law)),)


@dataclass(frozen=True)
class LawDispatch:
    """The laws' shared Warp types and the functions that dispatch to each strip's own law."""

    Parameters: Any
    Memory: Any
    History: Any
    fresh_memory: Any
    follow: Any
    last_curvature: Any
    elastic_moment: Any
    hysteretic_moment: Any
    tangent: Any
    follow_before_decay: Any
    decay: Any
    moment_along_path: Any
    law_of: Any
    """``law_of(p)``: the index in :data:`LAWS` of the law whose parameters ``p`` are."""
    own: tuple[LawFunctions, ...]
    """Each law's own functions (their ``follow`` split, kernels/law.py), by index, for a
    caller that takes the law's branch once for many hinges."""
    decays: tuple[bool, ...]
    """Whether each law's ``follow`` ends in an exponential decay of its own (a law that
    gives none is split with x = 0)."""


def split_follow(
    law: BendingLaw, functions: LawFunctions, scalar: Any, Parameters: Any, Memory: Any, History: Any
) -> LawFunctions:
    """``law``'s ``functions`` with ``follow_before_decay`` and ``decay`` (kernels/law.py): the law's
    own, or for a law that gives none its whole ``follow`` and no decay (x = 0)."""
    if functions.follow_before_decay is not None and functions.decay is not None:
        return functions
    if (functions.follow_before_decay is None) != (functions.decay is None):
        raise LawRegistryError(
            f"the {law.name} law gives one of follow_before_decay and decay; a law gives both or neither"
        )
    follow = functions.follow
    zero = scalar(0.0)

    @wp.func
    def follow_before_decay(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        return follow(curvature, memory, p, history, hinge, strip), zero

    @wp.func
    def decay(memory: Memory, factor: scalar, p: Parameters):
        return memory

    return replace(functions, follow_before_decay=follow_before_decay, decay=decay)


@functools.cache
def build(scalar: Any) -> LawDispatch:
    """The laws' Warp types, dispatching functions and path kernel for ``scalar``."""
    types = precision(scalar)
    Parameters, Memory, History = types.law_parameters, types.law_memory, types.reversal_memory
    zero = scalar(0.0)
    built = tuple(law.build(scalar) for law in LAWS)
    functions = tuple(
        split_follow(law, own, scalar, Parameters, Memory, History) for law, own in zip(LAWS, built, strict=True)
    )
    decays = tuple(f.decay is not None for f in built)

    @wp.func
    def law_of(p: Parameters):
        return int(p[LAW_SLOT])

    def dispatch(index: int) -> SimpleNamespace:
        # One function per law and method, each naming its law's own and the next law's
        # dispatch (Warp hashes the functions a function names, not those a loop's
        # wp.static picks, so an edited law never loads a stale cached kernel); an index
        # past the list (which the packing never writes) falls back to the first law.
        head = functions[index]
        rest = dispatch(index + 1) if index + 1 < len(functions) else functions[0]
        head_fresh, rest_fresh = head.fresh_memory, rest.fresh_memory
        head_follow, rest_follow = head.follow, rest.follow
        head_hysteretic, rest_hysteretic = head.hysteretic_moment, rest.hysteretic_moment
        head_tangent, rest_tangent = head.tangent, rest.tangent
        head_before_decay, rest_before_decay = head.follow_before_decay, rest.follow_before_decay
        head_decay, rest_decay = head.decay, rest.decay

        @wp.func
        def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
            if law_of(p) == wp.static(index):
                return head_fresh(curvature, p, history, hinge, strip)
            return rest_fresh(curvature, p, history, hinge, strip)

        @wp.func
        def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
            if law_of(p) == wp.static(index):
                return head_follow(curvature, memory, p, history, hinge, strip)
            return rest_follow(curvature, memory, p, history, hinge, strip)

        @wp.func
        def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
            if law_of(p) == wp.static(index):
                return head_hysteretic(curvature, memory, p)
            return rest_hysteretic(curvature, memory, p)

        @wp.func
        def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
            if law_of(p) == wp.static(index):
                return head_tangent(curvature, memory, p, history, hinge, strip)
            return rest_tangent(curvature, memory, p, history, hinge, strip)

        @wp.func
        def follow_before_decay(
            curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int
        ):
            if law_of(p) == wp.static(index):
                return head_before_decay(curvature, memory, p, history, hinge, strip)
            return rest_before_decay(curvature, memory, p, history, hinge, strip)

        @wp.func
        def decay(memory: Memory, factor: scalar, p: Parameters):
            if law_of(p) == wp.static(index):
                return head_decay(memory, factor, p)
            return rest_decay(memory, factor, p)

        return SimpleNamespace(
            fresh_memory=fresh_memory,
            follow=follow,
            hysteretic_moment=hysteretic_moment,
            tangent=tangent,
            follow_before_decay=follow_before_decay,
            decay=decay,
        )

    chain = dispatch(0)
    fresh_memory, follow = chain.fresh_memory, chain.follow
    hysteretic_moment, tangent = chain.hysteretic_moment, chain.tangent
    follow_before_decay, decay = chain.follow_before_decay, chain.decay

    @wp.func
    def elastic_moment(curvature: scalar, p: Parameters):
        return p[0] * curvature

    @wp.func
    def last_curvature(memory: Memory):
        return memory[LAST_CURVATURE_SLOT]

    @wp.kernel(module="unique", enable_backward=False)
    def moment_along_path(
        curvature_path: wp.array2d(dtype=scalar),
        parameters: wp.array(dtype=Parameters),
        history: History,
        moment: wp.array2d(dtype=scalar),
        slope: wp.array2d(dtype=scalar),
        work: wp.array(dtype=scalar),
    ):
        """Moment per width M and tangent dM/dK along curvature paths ``[sample, hinge]``.

        Each hinge starts fresh at its first sample (path s is hinge 0 of strip s in
        ``history``); ``work`` accumulates
        Σ M_n (K_{n+1} − K_n), the bending work per width with a left-point rule.
        """
        s = wp.tid()
        p = parameters[s]
        memory = fresh_memory(curvature_path[0, s], p, history, 0, s)
        w = zero
        for n in range(curvature_path.shape[0]):
            k = curvature_path[n, s]
            memory = follow(k, memory, p, history, 0, s)
            m = elastic_moment(k, p) + hysteretic_moment(k, memory, p)
            moment[n, s] = m
            slope[n, s] = tangent(k, memory, p, history, 0, s)
            if n + 1 < curvature_path.shape[0]:
                w = w + m * (curvature_path[n + 1, s] - k)
        work[s] = w

    return LawDispatch(
        Parameters=Parameters,
        Memory=Memory,
        History=History,
        fresh_memory=fresh_memory,
        follow=follow,
        last_curvature=last_curvature,
        elastic_moment=elastic_moment,
        hysteretic_moment=hysteretic_moment,
        tangent=tangent,
        follow_before_decay=follow_before_decay,
        decay=decay,
        moment_along_path=moment_along_path,
        law_of=law_of,
        own=functions,
        decays=decays,
    )
