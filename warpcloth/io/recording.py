"""Reading back what a run or a sweep wrote, for export, plots and renders.

A :class:`Recording` is the view every consumer shares: the variants' resolved scenes,
shape frames ``[frame, variant, node, xy]`` (m), probe series and the per-variant
parameters, read from a run directory (:mod:`.run_dir`) or a sweep directory
(:mod:`.sweep_dir`) by :func:`warpcloth.io.load.load_recording`. Frames are
memory-mapped, so selecting a few variants of a large sweep reads only theirs.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from warpcloth.core.result import checked_probe
from warpcloth.errors import ArgumentError, ArgumentTypeError, DataFileError, checked_index
from warpcloth.scene import COORDINATES, Scene, batch_fields, choice_fields, rest_positions


@dataclass
class Recording:
    """Frames, probes and parameters of selected variants of a run or sweep.

    ``variants`` holds the variant numbers as the run or sweep numbered them;
    ``frames[:, j]`` and ``probes[variants[j]]`` belong to ``scenes[j]``.
    """

    source: Path
    variants: np.ndarray
    scenes: list[Scene]
    frame_times: np.ndarray
    frames: np.ndarray
    probes: pd.DataFrame
    parameters: pd.DataFrame
    complete: bool = True

    @property
    def alive(self) -> np.ndarray:
        """``[frame, variant]``: whether the strip has a recorded shape (False after a
        divergence)."""
        return np.isfinite(self.frames).all(axis=(2, 3))

    @functools.cached_property
    def drawable_frames(self) -> np.ndarray:
        """Frames for drawing: a strip without a recorded shape (after it diverged) keeps
        its last recorded one, or its rest shape if it has none."""
        # Forward fill along time: each frame takes the latest recorded one at or before it;
        # a rest shape is prepended for strips with none yet.
        rest = np.stack([rest_positions(scene) for scene in self.scenes])
        filled = np.concatenate([rest[None], self.frames])
        alive = np.concatenate([np.ones((1, len(self.scenes)), dtype=bool), self.alive])
        latest = np.maximum.accumulate(np.where(alive, np.arange(len(filled))[:, None], 0), axis=0)
        return filled[latest, np.arange(len(self.scenes))[None, :]][1:]

    def nearest_frames(self, times: np.ndarray) -> np.ndarray:
        """Indices of the frames nearest to ``times`` (s from t = 0: the release, or the clamp motion's start)."""
        return nearest_frames(self.frame_times, times)

    @property
    def varying(self) -> list[str]:
        """The parameters that differ between the selected variants, in column order."""
        return [c for c in self.parameters.columns if c != "variant" and self.parameters[c].nunique() > 1]

    @property
    def frame_rate(self) -> float:
        """Shape frames per second."""
        return self.scenes[0].output.frame_rate_hz

    @property
    def n_clamped(self) -> int:
        """Clamp nodes at the top of every strip."""
        return self.scenes[0].n_clamped

    def probe(self, name: str, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Times and values of one probe of the j-th selected variant (0 … n − 1)."""
        name = checked_probe(name)
        rows = self.probes[
            self.probes["variant"] == self.variants[checked_index("j", j, len(self.variants), "selected variants")]
        ]
        return rows["t"].to_numpy(), rows[name].to_numpy()

    def to_dataframe(self) -> pd.DataFrame:
        """The probes in long form (t, variant, one column per probe, SI) joined with each
        variant's parameters: ready for groupby and plotting."""
        return self.probes.merge(self.parameters, on="variant", how="left")

    def to_xarray(self) -> object:
        """An ``xarray.Dataset``: every probe as a variable over (t, variant), the frames
        over (frame_time, variant, node, xy), the per-variant parameters as coordinates
        along ``variant``, units in ``attrs``;
        the layout of :meth:`warpcloth.strip.RunResult.to_xarray`."""
        from warpcloth.core.labelled import probes_dataset
        from warpcloth.kernels import PROBE_FIELDS

        # samples a strip never reached (after its divergence) are NaN, as in memory
        table = self.probes.pivot_table(index="t", columns="variant", values=list(PROBE_FIELDS), dropna=False)
        table = table.reindex(columns=pd.MultiIndex.from_product([PROBE_FIELDS, self.variants]))
        probes = table.to_numpy().reshape(len(table), len(PROBE_FIELDS), len(self.variants))
        parameters = self.parameters.set_index("variant").loc[self.variants]
        return probes_dataset(
            table.index.to_numpy(),
            probes,
            self.frame_times,
            self.frames,
            self.variants,
            {name: parameters[name].to_numpy() for name in parameters.columns},
            {
                "source": str(self.source),
                "complete": int(self.complete),
                "coordinates": f"{COORDINATES}; t = 0 at the release",
            },
        )

    def clamp_pose(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Per frame, the clamp's rotation angle (rad) and translation (m) that carry its
        rest nodes onto the recorded ones (a rigid motion, least squares)."""
        rest = rest_positions(self.scenes[j])[: self.n_clamped]
        moved = self.drawable_frames[:, j, : self.n_clamped]
        rest_c = rest - rest.mean(axis=0)
        moved_c = moved - moved.mean(axis=1, keepdims=True)
        cross = (rest_c[None, :, 0] * moved_c[..., 1] - rest_c[None, :, 1] * moved_c[..., 0]).sum(axis=1)
        dot = (rest_c[None] * moved_c).sum(axis=(1, 2))
        angle = np.arctan2(cross, dot)
        c, s = np.cos(angle), np.sin(angle)
        centre = rest.mean(axis=0)
        rotated = np.stack([c * centre[0] - s * centre[1], s * centre[0] + c * centre[1]], axis=-1)
        return angle, moved.mean(axis=1) - rotated


def parse_variants(text: str | int | Sequence[int] | None, n_variants: int) -> np.ndarray:
    """Variant numbers from ``"3"``, ``"0:50"``, ``"0:50:5"`` or ``"1,4,9"`` (None: all; from
    Python also an int or a list of ints). A negative number is refused, never counted
    from the end."""
    if text is None:
        return np.arange(n_variants)
    if isinstance(text, (list, tuple)) and all(isinstance(v, int) and not isinstance(v, bool) for v in text):
        text = ",".join(map(str, text))
    elif isinstance(text, int) and not isinstance(text, bool):
        text = str(text)
    elif not isinstance(text, str):
        raise ArgumentTypeError(
            "variants",
            f"must be a selection such as '3', '1,4,9' or '0:50' (or an int or a list of ints), got {text!r}",
        )
    text = text.strip()
    try:
        parts = [int(p) if p else None for p in text.split(":")] if ":" in text else None
        chosen = None if parts else np.array([int(p) for p in text.split(",")])
    except ValueError:
        raise ArgumentError("variants", f"{text!r} is not a variant number, list (1,4,9) or range (0:50)") from None
    if parts is not None:
        if len(parts) > 3 or any(p is not None and p < 0 for p in parts) or parts[2:3] == [0]:
            raise ArgumentError(
                "variants",
                f"{text!r}: a range is START:STOP[:STEP] of numbers ≥ 0 (a step > 0); it never counts from the end",
            )
        chosen = np.arange(n_variants)[slice(*parts)]
    if len(chosen) == 0:
        raise ArgumentError("variants", f"{text!r} selects no variant of {n_variants}")
    if len(np.unique(chosen)) != len(chosen):
        raise ArgumentError("variants", f"{text!r} names a variant twice")
    bad = chosen[(chosen < 0) | (chosen >= n_variants)]
    if len(bad):
        raise ArgumentError("variants", f"variant {bad[0]} does not exist (there are {n_variants})")
    return chosen


_FILTER = re.compile(r"^\s*([\w.]+)\s*(<=|>=|==|!=|<|>)\s*(\S+)\s*$")


def filter_variants(parameters: pd.DataFrame, where: str) -> np.ndarray:
    """Variant numbers whose parameters satisfy every ``field OP value`` clause of
    ``where`` (clauses separated by commas, OP one of < <= > >= == !=)."""
    keep = np.ones(len(parameters), dtype=bool)
    for clause in where.split(","):
        match = _FILTER.match(clause)
        if not match:
            raise ArgumentError("where", f"{clause.strip()!r} is not 'field OP value' (e.g. damping.gamma_per_s<0.5)")
        name, op, value = match.groups()
        if name not in parameters:
            raise ArgumentError(
                "where",
                f"{name!r} is not a parameter of these variants; "
                f"known: {', '.join(c for c in parameters.columns if c != 'variant')}",
            )
        column = parameters[name]
        if not pd.api.types.is_numeric_dtype(column):  # a choice, e.g. material.bending_law==dahl
            if op not in ("==", "!="):
                raise ArgumentError(
                    "where",
                    f"{name} is a choice ({', '.join(sorted(set(column)))}): compare it with == or !=, not {op}",
                )
            same = (column == value.strip("\"'")).to_numpy()
            keep &= same if op == "==" else ~same
            continue
        try:
            number = float(value)
        except ValueError:
            raise ArgumentError("where", f"{value!r} in {clause.strip()!r} is not a number") from None
        keep &= {
            "<": column < number,
            "<=": column <= number,
            ">": column > number,
            ">=": column >= number,
            "==": column == number,
            "!=": column != number,
        }[op].to_numpy()
    chosen = parameters["variant"].to_numpy()[keep]
    if len(chosen) == 0:
        raise ArgumentError("where", f"{where!r} matches no variant")
    return chosen


def per_strip_parameters(scenes: list[Scene]) -> pd.DataFrame:
    """One row per scene: every scalar field that may vary per strip (dotted names), and
    every per-strip choice (a string field with a fixed set of values, e.g.
    ``material.bending_law``), so variants that differ only in a choice can be told apart."""
    fixed = set(batch_fields())
    choices = set(choice_fields())
    rows = []
    for scene in scenes:
        row = {}
        for section, values in scene.to_dict().items():
            for key, value in values.items():
                name = f"{section}.{key}"
                if name not in fixed and isinstance(value, (int, float)) and not isinstance(value, bool):
                    row[name] = float(value)
                elif name in choices and name not in fixed:
                    row[name] = value
        rows.append(row)
    return pd.DataFrame(rows)


def select_variants(parameters: pd.DataFrame, variants: str | None, where: str | None) -> np.ndarray:
    """Variant numbers chosen by a ``--variants`` selection and a ``--where`` filter (both optional)."""
    chosen = parse_variants(variants, len(parameters))
    if where:
        chosen = np.intersect1d(chosen, filter_variants(parameters.iloc[chosen], where))
    return chosen


def select_summary_rows(summary: pd.DataFrame, variants: str | None, where: str | None, total: int) -> pd.DataFrame:
    """The rows of a sweep's summary (one per finished variant, a ``variant`` column and
    the parameters) that a ``--variants`` selection of the sweep's ``total`` variants and a
    ``--where`` filter choose; an ArgumentError naming the one that leaves none."""
    rows = summary
    if variants is not None:
        rows = rows[rows["variant"].isin(parse_variants(variants, total))]
        if rows.empty:
            raise ArgumentError("variants", f"{variants!r} selects no variant the sweep has finished")
    if where:
        rows = rows[rows["variant"].isin(filter_variants(rows, where))]
    return rows


def check_time_order(
    path: Path, t: np.ndarray, variant: np.ndarray, line_offset: int | None = None, index: str = "variant"
) -> None:
    """Refuse stored probe rows whose times do not increase within each variant (rows
    reordered after the run: same counts and sizes, but every period read from them
    would be wrong). ``line_offset`` turns a row index into the file's line (None: a file
    without lines, e.g. Parquet, where the row is named instead); ``index`` names what
    ``variant`` counts (a sheet run's ``sheet``)."""
    order = np.argsort(variant, kind="stable")
    same = variant[order][1:] == variant[order][:-1]
    back = np.flatnonzero(same & ~(np.diff(t[order]) > 0))  # NaN is out of order too
    if len(back):
        row, before = int(order[back[0] + 1]), int(order[back[0]])
        where = f"row {before + 1}" if line_offset is None else f"line {before + line_offset}"
        raise DataFileError(
            path,
            f"t = {t[row]:.10g} s of {index} {variant[row]} comes after t = {t[before]:.10g} s "
            f"({where}): the rows are out of time order, so the file was changed after it was "
            "written",
            None if line_offset is None else row + line_offset,
        )


def nearest_frames(frame_times: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Indices into ``frame_times`` of the frames nearest to ``times``; an ArgumentError of
    ``times`` for a time outside them."""
    times = np.atleast_1d(np.asarray(times, dtype=float))
    late = times[(times < frame_times[0] - 1e-9) | (times > frame_times[-1] + 1e-9)]
    if len(late):
        raise ArgumentError(
            "times", f"{late[0]:g} s is outside the recording ({frame_times[0]:g} to {frame_times[-1]:g} s)"
        )
    return np.abs(frame_times[None, :] - times[:, None]).argmin(axis=1)
