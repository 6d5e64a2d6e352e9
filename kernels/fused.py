"""What every body's fused kernel shares: the advance loop, the stop, the sum of the
internal forces and the energy tally (docs/model.md §9, §10).

A body (kernels/strip.py, kernels/sheet.py) supplies its structs, a ``substep(model,
control, stepping, state, s, step) -> (code, index, value)`` and a ``record_probes(model,
control, stepping, state, settings, s, step, probes, k) -> energy``; :func:`build_advance`
generates from them the one kernel that takes every body of a batch through many
substeps per launch, recording at each output step. The tally of the work done is a
vector with one named channel per work probe (:class:`~.probe_set.ProbeSet`).
"""

import functools
from typing import Any

import warp as wp

from .status import STATUS_NONFINITE_ENERGY, STATUS_OK


@functools.cache
def tally_type(scalar: Any, channels: int) -> Any:
    """The energy tally of a body with ``channels`` work channels."""
    return wp.types.vector(length=channels, dtype=scalar)


@functools.cache
def channel(scalar: Any, tally: Any, slot: int) -> Any:
    """``only(value)``: a tally holding ``value`` in channel ``slot`` and 0 elsewhere."""

    @wp.func
    def only(value: scalar):
        t = tally()
        t[wp.static(slot)] = value
        return t

    return only


@functools.cache
def internal_forces(State: Any) -> Any:
    """``internal_force(state, i, s)``: the laws' force on node ``i`` of body ``s``, the one
    place the three kinds are summed."""

    @wp.func
    def internal_force(state: State, i: int, s: int):
        return state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]

    return internal_force


@functools.cache
def law_work(State: Any, vec: Any, tally: Any, elastic: int, hysteretic: int) -> Any:
    """``work_on(state, i, s, displacement)``: the work done against the laws' elastic and
    hysteretic forces at node ``i`` over ``displacement``, in their channels. Callers pass
    the centred displacement (x_{n+1} − x_{n−1}) / 2: the left-point F_n·(x_{n+1} − x_n)
    would add ½ΔxᵀHΔx every step, an O(dt) drift of the budget (docs/model.md §10.3)."""

    @wp.func
    def work_on(state: State, i: int, s: int, displacement: vec):
        t = tally()
        t[wp.static(elastic)] = -wp.dot(state.force_elastic[i, s], displacement)
        t[wp.static(hysteretic)] = -wp.dot(state.force_hysteretic[i, s], displacement)
        return t

    return work_on


@functools.cache
def tally_recorder(scalar: Any, tally: Any, slots: tuple[int, ...], signs: tuple[int, ...], first: int = 0) -> Any:
    """``record_work(probes, k, s, work, stored) -> energy``: writes each channel of the tally
    ``work`` from ``first`` on into its probe slot (``slots``) of sample ``k`` and returns
    ``stored`` plus the channels of the work done against forces (``signs`` +1): the
    budget's sum without the work done by prescribed motion, which a caller checks is
    finite. One function per channel, each naming the next: Warp hashes what a function
    names, not what a loop's wp.static picks, so two layouts never share a cached kernel."""
    if first == len(slots):

        @wp.func
        def recorded(probes: wp.array3d(dtype=scalar), k: int, s: int, work: tally, stored: scalar):
            return stored

        return recorded
    rest = tally_recorder(scalar, tally, slots, signs, first + 1)
    slot, against = slots[first], signs[first] > 0

    @wp.func
    def record_work(probes: wp.array3d(dtype=scalar), k: int, s: int, work: tally, stored: scalar):
        probes[k, wp.static(slot), s] = work[wp.static(first)]
        energy = stored
        if wp.static(against):
            energy = energy + work[wp.static(first)]
        return rest(probes, k, s, work, energy)

    return record_work


@functools.cache
def stopper(State: Any, scalar: Any) -> Any:
    """``stop(state, s, code, step, index, value)``: body ``s`` stops, saying why."""

    @wp.func
    def stop(state: State, s: int, code: int, step: int, index: int, value: scalar):
        state.status[s] = code
        state.status_step[s] = step
        state.status_index[s] = index
        state.status_value[s] = value
        state.step[s] = step

    return stop


def build_advance(
    Model: Any,
    Control: Any,
    Stepping: Any,
    State: Any,
    Settings: Any,
    scalar: Any,
    position: Any,
    substep: Any,
    record_probes: Any,
) -> Any:
    """The fused ``advance`` kernel of a body from its structs, its ``substep`` and its
    ``record_probes`` (see the module's docstring); ``position`` is its node vector type."""
    stop = stopper(State, scalar)

    @wp.kernel(module="unique", enable_backward=False)
    def advance(
        model: Model,
        control: Control,
        stepping: Stepping,
        state: State,
        settings: Settings,
        output_steps: wp.array(dtype=int),
        first_output: int,
        first_frame: int,
        probes: wp.array3d(dtype=scalar),
        frames: wp.array3d(dtype=position),
        first_body: int,
    ):
        """Advance bodies ``first_body`` … ``first_body + dim − 1`` to each output step in
        turn, recording probes (and frames); a batch may be split into such ranges, each
        launched from its own CPU thread (every body is independent)."""
        s = first_body + wp.tid()
        if state.status[s] != STATUS_OK:
            return
        step = state.step[s]
        for k in range(output_steps.shape[0]):
            while step < output_steps[k]:
                code, index, value = substep(model, control, stepping, state, s, step)
                if code != STATUS_OK:
                    stop(state, s, code, step, index, value)
                    return
                step += 1
            energy = record_probes(model, control, stepping, state, settings, s, step, probes, k)
            if not wp.isfinite(energy):
                stop(state, s, STATUS_NONFINITE_ENERGY, step, -1, energy)
                return
            output = first_output + k
            if output >= 0 and output % settings.probes_per_frame == 0 and frames.shape[0] > 0:
                f = output / settings.probes_per_frame - first_frame
                for i in range(model.n_nodes):
                    frames[f, i, s] = state.position[i, s]
        state.step[s] = step

    return advance
