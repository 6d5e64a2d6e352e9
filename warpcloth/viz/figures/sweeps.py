"""The figure of a sweep: a metric against one swept parameter, or a heat map over two."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd

from warpcloth.errors import ArgumentError, DataFileError

from . import common
from .common import DPI, LEGEND_VARIANTS, field_label, field_unit, plt

JOINED_VALUES = 8
"""A curve over fewer swept values is drawn as points: a line through three points says
the response between them is straight, which a finer grid often shows it is not."""


def read_sweep_summary(sweep_dir: str | Path) -> pd.DataFrame:
    """Per-variant summary of a sweep (the merged file, or the finished batches so far)."""
    from warpcloth.io.sweep_dir import read_parquet

    sweep_dir = Path(sweep_dir)
    if not (sweep_dir / "sweep.json").is_file():
        raise DataFileError(
            sweep_dir, "is not a sweep directory (no sweep.json); --metric and --x plot a sweep's summary"
        )
    merged = sweep_dir / "summary.parquet"
    if merged.is_file():
        return read_parquet(merged)
    parts = sorted((sweep_dir / "summary").glob("batch-*.parquet"))
    if not parts:
        raise DataFileError(sweep_dir, "the sweep has no finished batch yet")
    return pd.concat([read_parquet(p) for p in parts]).sort_values("variant")


def plot_sweep(
    summary: pd.DataFrame, path: str | Path, metric: str, x: str, y: str | None = None, *, dpi: float = DPI
) -> Path:
    """:func:`sweep_figure` written to ``path`` (its suffix chooses the format)."""
    return common.save(sweep_figure(summary, metric, x, y), Path(path), dpi)


def sweep_figure(summary: pd.DataFrame, metric: str, x: str, y: str | None = None) -> plt.Figure:
    """A metric against one swept parameter (a line for a 1-D sweep; points coloured by
    another swept field for a sampled one; a line per value of one other gridded field
    with few values, e.g. the bending law; points and their mean when more are gridded)
    or two (heat map on a grid, categories such as the law included; coloured points
    otherwise)."""
    data, missing = _plotted(summary, metric, x, y)
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    if y is None:
        _against_one(fig, ax, data, metric, x)
    else:
        _heat_map(fig, ax, data, metric, x, y)
    diverged = len(summary) - len(data) - missing
    notes = [f"{diverged} diverged"] * bool(diverged) + [f"{missing} without a value"] * bool(missing)
    ax.set_title(
        f"{field_label(metric, units=False)} over {len(data)} variants" + (f" ({', '.join(notes)})" if notes else "")
    )
    return fig


def _plotted(summary: pd.DataFrame, metric: str, x: str, y: str | None) -> tuple[pd.DataFrame, int]:
    # The variants to plot (not diverged, with a value of the metric) and how many have no
    # value; an ArgumentError names a column the figure cannot plot.
    for argument, name in (("metric", metric), ("x", x), ("y", y)):
        if name is not None and name not in summary:
            raise ArgumentError(
                argument,
                f"{name!r} is not a column of the sweep summary; "
                f"known: {', '.join(c for c in summary.columns if c not in ('variant', 'batch'))}",
            )
    if y is not None and y == x:
        raise ArgumentError("y", f"{y!r} is already on the x axis; a heat map needs two different parameters")
    if summary[metric].map(lambda v: isinstance(v, (list, np.ndarray))).any():
        raise ArgumentError(
            "metric",
            f"{metric!r} holds a list per variant (one value per half-cycle); plot one "
            "number per variant, e.g. mean_log_decrement or first_amplitude_m",
        )
    if not pd.api.types.is_numeric_dtype(summary[metric]) or pd.api.types.is_bool_dtype(summary[metric]):
        raise ArgumentError(
            "metric",
            f"{metric!r} is not a number per variant (it holds "
            f"{summary[metric].dtype}); plot a numeric column, e.g. first_period_s or mean_log_decrement",
        )
    data = summary[~summary["diverged"]] if "diverged" in summary else summary
    valued = data[np.isfinite(data[metric].to_numpy(dtype=float))]
    if valued.empty:
        raise ArgumentError(
            "metric",
            f"no variant has a value of "
            f"{metric!r} (every one is NaN: for a period or decrement, the record may be shorter "
            "than the swing needs, or the strip does not swing); plot another metric or run longer",
        )
    return valued, len(data) - len(valued)


def _against_one(fig: plt.Figure, ax: plt.Axes, data: pd.DataFrame, metric: str, x: str) -> None:
    # The metric against one swept parameter (sweep_figure's cases).
    grouped = data.groupby(x)[metric]
    # swept fields are dotted scene names; others that vary make this a sample, not a curve
    others = [c for c in data.columns if "." in c and c != x and data[c].nunique() > 1]
    style = "o-" if data[x].nunique() >= JOINED_VALUES else "o"
    if grouped.size().max() == 1 and not others:
        ordered = data.sort_values(x)
        ax.plot(ordered[x], ordered[metric], style, ms=3)
    elif grouped.size().max() == 1:
        # a sampled sweep (Latin hypercube): points coloured by another swept field,
        # never joined in x order (that draws a zigzag through unrelated variants)
        colour = data[others[0]]
        if not pd.api.types.is_numeric_dtype(colour):  # a choice: one colour per value, in a legend
            for value, part in data.groupby(others[0], sort=False):
                ax.scatter(part[x], part[metric], s=12, label=f"{field_label(others[0], units=False)} = {value}")
            ax.legend(fontsize=7)
        else:
            points = ax.scatter(data[x], data[metric], c=colour, s=12, cmap="viridis")
            fig.colorbar(points, ax=ax, label=field_label(others[0]))
    elif len(others) == 1 and data[others[0]].nunique() <= LEGEND_VARIANTS:
        # one other gridded field with few values (e.g. the bending law): a line each
        for value, part in data.groupby(others[0], sort=False):
            ordered = part.sort_values(x)
            shown = f"{value:g} {field_unit(others[0])}".rstrip() if isinstance(value, float) else str(value)
            label = f"{field_label(others[0], units=False)} = {shown}"
            ax.plot(ordered[x], ordered[metric], style, ms=3, label=label)
        ax.legend(fontsize=7)
    else:
        ax.plot(data[x], data[metric], ".", ms=3, alpha=0.6, label="variants (other parameters vary)")
        ax.plot(grouped.mean().index, grouped.mean().to_numpy(), "k" + style[-1], lw=1, ms=4, label="mean")
        ax.legend(fontsize=7)
    if style == "o":
        note = f"{data[x].nunique()} values of {field_label(x, units=False)}: points, not joined"
        ax.text(0.99, 0.01, note, ha="right", va="bottom", fontsize=7, color="0.4", transform=ax.transAxes)
    ax.set(xlabel=field_label(x), ylabel=field_label(metric))


def _heat_map(fig: plt.Figure, ax: plt.Axes, data: pd.DataFrame, metric: str, x: str, y: str) -> None:
    # The metric over two swept parameters: cells on a full grid, coloured points otherwise.
    table = data.pivot_table(index=y, columns=x, values=metric, aggfunc="mean")
    mesh: matplotlib.cm.ScalarMappable
    # Colours span the 2nd–98th percentile, so one outlier does not flatten the map.
    lo, hi = np.nanpercentile(data[metric], [2, 98])
    scale = {"cmap": "viridis", "vmin": lo, "vmax": hi if hi > lo else None}
    if table.size == len(data) and not table.isna().any().any():
        # one equal cell per grid value, at 0, 1, 2, ..., labelled at its centre
        mesh = ax.pcolormesh(
            np.arange(table.shape[1]), np.arange(table.shape[0]), table.to_numpy(), shading="nearest", **scale
        )
        _cell_ticks(ax.xaxis, table.columns)
        _cell_ticks(ax.yaxis, table.index)
    else:
        mesh = ax.scatter(data[x], data[y], c=data[metric], s=14, **scale)
    fig.colorbar(mesh, ax=ax, label=field_label(metric), extend="both")
    ax.set(xlabel=field_label(x), ylabel=field_label(y))


HEAT_MAP_TICKS = 12
"""A heat-map axis labels at most this many of its cells (every k-th beyond)."""


def _cell_ticks(axis: matplotlib.axis.Axis, values: pd.Index) -> None:
    # The grid's cells are drawn one per value at 0, 1, 2, ...: a tick at the centre of
    # each, labelled with the swept value it holds. On the values' own scale an uneven
    # grid's cells would be uneven and a value's tick off its cell's centre (the cell
    # edges lie halfway to the neighbours), and the locator's round numbers fell anywhere.
    step = -(-len(values) // HEAT_MAP_TICKS)
    shown = range(0, len(values), step)
    axis.set_ticks(list(shown), [f"{values[i]:.4g}" if isinstance(values[i], float) else str(values[i]) for i in shown])
