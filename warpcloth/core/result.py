"""What a run recorded, for any body: probes over time, the recorder's other tables (a
sheet's markers), shape frames, the divergences and the cost, in SI units."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from warpcloth.errors import ArgumentError, checked_index
from warpcloth.kernels.probe_set import ProbeSet
from warpcloth.kernels.probes import STRIP_PROBES


def reversal_memory_warning(report: dict[str, object]) -> str | None:
    """The warning a run with overflowed reversal memory prints (see
    :attr:`RunResult.reversal_memory`); None when nothing overflowed."""
    overflows = np.asarray(report.get("overflows", []), dtype=int)
    if not overflows.any():
        return None
    bodies = np.flatnonzero(overflows)
    named = ", ".join(f"{s} ({overflows[s]})" for s in bodies[:8]) + (" …" if len(bodies) > 8 else "")
    return (
        f"the masing reversal memory ({report['capacity']} points per hinge) was full: {int(overflows.sum())} "
        f"reversal(s) not stored in variant(s) {named}; their inner loops were traced without hysteresis, so the "
        "hysteresis work is underestimated by their area; raise integrator.reversal_memory"
    )


def checked_probe(name: object, probe_set: ProbeSet = STRIP_PROBES) -> str:
    """``name`` if it is one of ``probe_set``'s probes, else an ArgumentError listing them."""
    if not isinstance(name, str) or name not in probe_set.index:
        raise ArgumentError("name", f"{name!r} is not a probe; the probes are {', '.join(probe_set.fields)}")
    return name


@dataclass
class RunResult:
    """Everything a run of a batch recorded, in SI units; the same for strips and sheets.

    ``probes`` is ``[sample, field, variant]`` (fields: :attr:`probe_set`) at times ``t``;
    ``frames`` is ``[frame, variant, node, xy or xyz]`` at ``frame_times``; ``tables``
    holds the recorder's other per-sample records (a sheet's ``markers[sample, variant,
    marker, xyz]``). Samples after a variant's divergence are NaN here (and absent from a
    run directory's tables). ``scenes`` holds what each variant was built from, when it
    was built from scenes.
    """

    scenes: list[Any]
    t: np.ndarray
    probes: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray | None
    diverged: list[Any] = field(default_factory=list)
    wall_time_s: float = 0.0
    body_steps: int = 0
    """The steps every variant ran, summed (the hold's included; a diverged one's to its stop)."""
    parameters: dict[str, np.ndarray] = field(default_factory=dict)
    """Each variant's value of every per-variant scalar scene field, by dotted name (filled
    when the batch was built from scenes): the coordinates of :meth:`to_xarray`."""
    attrs: dict[str, object] = field(default_factory=dict)
    """What :meth:`to_xarray` says about the whole result (e.g. its coordinate frame)."""
    reversal_memory: dict[str, object] = field(default_factory=dict)
    """For a batch with return-point memory (the masing law): the points each hinge could
    keep (``capacity``) and, per variant, the ``deepest`` any hinge went and the
    ``overflows`` (reversals not stored: their inner loops were traced without
    hysteresis, docs/model.md §4.10). Empty otherwise."""
    tables: dict[str, np.ndarray] = field(default_factory=dict)
    probe_set: ProbeSet = STRIP_PROBES
    body: str = "strip"
    n_nodes: int = 0
    geometry: Any = None
    """A sheet's :class:`~warpcloth.sheet.SheetGeometry` (None for strips)."""
    metrics: pd.DataFrame | None = None
    """One row per variant, when scenes were run (:func:`warpcloth.simulate`): what ``warpcloth
    run`` prints and a sweep's summary holds (a strip's first period, amplitude and log
    decrement, a sheet's marker amplitudes, the divergence), in the summary's columns."""

    @property
    def strip_steps(self) -> int:
        """:attr:`body_steps`, under the name a strip's throughput is quoted in."""
        return self.body_steps

    @property
    def node_steps(self) -> int:
        """Node updates done: :attr:`body_steps` × the nodes of a body."""
        return self.body_steps * self.n_nodes

    @property
    def markers(self) -> np.ndarray:
        """A sheet's markers ``[sample, variant, marker, xyz]`` (m), NaN after a divergence."""
        if "markers" not in self.tables:
            raise ArgumentError("markers", f"a {self.body} run records none; its tables are {list(self.tables)}")
        return self.tables["markers"]

    def memory_warning(self) -> str | None:
        """A sentence naming the variants whose reversal memory overflowed, or None."""
        return reversal_memory_warning(self.reversal_memory)

    def probe(self, name: str, variant: int | None = None) -> np.ndarray:
        """Time series of one probe: ``[sample, variant]``, or ``[sample]`` for one variant
        (an index 0 … n − 1; a name or index that is not one is refused, naming it)."""
        series = self.probes[:, self.probe_set.index[checked_probe(name, self.probe_set)], :]
        return series if variant is None else series[:, checked_index("variant", variant, series.shape[1], "variants")]

    def energy_total(self) -> np.ndarray:
        """The budget that should stay constant, ``[sample, variant]``: the energies the
        body holds and the work done against its forces, less the work done by the drives
        (the probe set's description, docs/model.md §10)."""
        return self.probe_set.energy_total(self.probes)

    def to_xarray(self) -> object:
        """An ``xarray.Dataset`` of the probes over (t, variant), the frames over
        (frame_time, variant, node, xy) and :attr:`parameters` as coordinates along
        ``variant``, units in ``attrs``."""
        from .labelled import probes_dataset

        return probes_dataset(
            self.t,
            self.probes,
            self.frame_times,
            self.frames,
            np.arange(self.probes.shape[2]),
            self.parameters,
            self.attrs,
            self.probe_set,
        )

    def to_dataframe(self) -> pd.DataFrame:
        """The probes in long form (t, variant, one column per probe, SI) joined with
        :attr:`parameters`: ready for groupby and plotting."""
        from .labelled import probes_frame

        return probes_frame(self.t, self.probes, np.arange(self.probes.shape[2]), self.parameters, self.probe_set)
