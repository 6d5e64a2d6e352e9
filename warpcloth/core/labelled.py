"""Recorded results as labelled arrays, for analysis in xarray or pandas: the one
layout shared by an in-memory :class:`~warpcloth.core.result.RunResult` and a
:class:`~warpcloth.io.recording.Recording` read back from disk."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from warpcloth.kernels.probe_set import ProbeSet
from warpcloth.kernels.probes import STRIP_PROBES


def probes_dataset(
    t: np.ndarray,
    probes: np.ndarray,
    frame_times: np.ndarray,
    frames: np.ndarray | None,
    variants: np.ndarray,
    parameters: Mapping[str, np.ndarray],
    attrs: Mapping[str, object],
    probe_set: ProbeSet = STRIP_PROBES,
) -> object:
    """An ``xarray.Dataset``: each probe of ``probes[sample, field, variant]`` a variable
    over (t, variant), ``frames[frame, variant, node, xy]`` (if any) over (frame_time,
    variant, node, xy), ``parameters`` (one value per variant, by dotted scene name) as
    coordinates along ``variant``, units in each variable's ``attrs``."""
    import xarray as xr  # on first use: pandas' import alone is heavy enough

    dataset = xr.Dataset(
        {
            name: (("t", "variant"), probes[:, k, :], {"units": probe_set.units[name]})
            for k, name in enumerate(probe_set.fields)
        },
        coords={"t": ("t", t, {"units": "s"}), "variant": np.asarray(variants)},
    )
    if frames is not None:
        axes = "xyz"[: frames.shape[-1]]
        dataset["frames"] = xr.DataArray(
            frames,
            dims=("frame_time", "variant", "node", axes),
            coords={"frame_time": ("frame_time", frame_times, {"units": "s"}), axes: list(axes)},
            attrs={"units": "m"},
        )
    dataset = dataset.assign_coords({name: ("variant", np.asarray(values)) for name, values in parameters.items()})
    dataset.attrs.update(attrs)
    return dataset


def probes_frame(
    t: np.ndarray,
    probes: np.ndarray,
    variants: np.ndarray,
    parameters: Mapping[str, np.ndarray],
    probe_set: ProbeSet = STRIP_PROBES,
) -> pd.DataFrame:
    """``probes[sample, field, variant]`` in long form (t, variant, one column per probe,
    SI; samples a strip never reached left out) joined with each variant's parameters."""
    n_samples, _, n_variants = probes.shape
    table = pd.DataFrame(
        {"t": np.repeat(t, n_variants), "variant": np.tile(np.asarray(variants), n_samples)}
        | {name: probes[:, k, :].reshape(-1) for k, name in enumerate(probe_set.fields)}
    )
    table = table[np.isfinite(probes).any(axis=1).reshape(-1)].reset_index(drop=True)
    labels = pd.DataFrame({"variant": np.asarray(variants)} | {k: np.asarray(v) for k, v in parameters.items()})
    return table.merge(labels, on="variant", how="left")
