"""Parameter sweeps: the ``[sweep]`` section of a scene, expanded into variants and batches.

A sweep varies scene fields given by dotted name (list items by index, e.g.
``material.tensile_gf_per_cm.3``)::

    [sweep]
    seed = 1                                   # for random sampling
    [sweep.grid]                               # Cartesian product
    "material.hysteresis_d1_gf_cm_per_cm" = [0.0, 0.02, 0.04]
    [sweep.zip]                                # parallel lists, one variant per position
    "clamp.rotation_centre_dy_mm" = [0.0, 1.4, 2.8]
    "damping.gamma_per_s" = [0.1, 0.2, 0.3]
    [sweep.random]                             # seeded sampling inside ranges
    method = "latin_hypercube"                 # or "uniform"
    samples = 100
    ranges = { "material.hysteresis_alpha_cm" = [2.0, 8.0] }

The variants are grid × zip × random (each block optional), in that nesting order, so
the expansion is deterministic under the seed. Fields that cannot vary inside one batch
(spacing, dt, durations, integrator, ...) split the variants into separate batches.

A sheet scene (a ``[sheet]`` table) sweeps the same way over its own fields: its variants
are :class:`~warpcloth.scene.sheet.SheetScene` objects, each checked by
:func:`~warpcloth.scene.sheet_build.check_sheet_scene`, and what a batch of sheets shares
(:data:`~warpcloth.scene.sheet_build.SHARED_SECTIONS`, the settling time) splits them.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from warpcloth import bodies
from warpcloth.core.resources import check_memory
from warpcloth.errors import ArgumentError, SceneError, checked_instance

from .files import read_scene_file, scene_source, strip_scene_from_dict
from .keys import is_material_file_key, key_path, key_path_or_none, overlaps
from .locate import located, variant_error
from .overrides import apply_overrides, set_field
from .sampling import discrepancy, latin_hypercube
from .schema import Scene, batch_fields
from .sheet import SheetScene
from .step import check_step, with_chosen_step

MAX_VARIANTS = 100_000
"""Default cap on a sweep's variants: each is a validated scene held in memory (a few kB,
~1 ms to build), so a million would take many minutes and gigabytes before any runs."""

VARIANT_BYTES = 20_000
"""Memory one expanded variant takes (its validated scene, assignment and samples): an
upper bound, for the check before a sweep is expanded."""

SWEEP_KEYS = {"seed", "grid", "zip", "random"}
RANDOM_KEYS = {"method", "samples", "ranges"}
METHODS = ("uniform", "latin_hypercube")


def strip_batch_key(scene: Scene) -> str:
    """What strips sharing one launch sequence must agree on (:func:`batch_fields`)."""
    d = scene.to_dict()
    return json.dumps([d[n.split(".")[0]][n.split(".")[1]] for n in batch_fields()])


def strip_variant(data: dict) -> Scene:
    """One strip variant of a sweep, its step not yet chosen (the sweep picks one for all)."""
    return strip_scene_from_dict(data, choose_step=False)


def strip_variants(scenes: list, assignments: list[dict[str, Any]]) -> list[Scene]:
    """The strip variants ready to run: one step for every variant that asks auto for one
    (checked by :func:`load_sweep` before a run)."""
    return with_chosen_step(scenes)


@dataclass
class Sweep:
    """An expanded sweep: one resolved scene per variant (strips' :class:`Scene` or
    sheets' :class:`SheetScene`), and what each one set."""

    base: dict  # raw base scene (without [sweep])
    spec: dict  # the raw [sweep] section
    keys: list[str]  # swept fields, in column order
    assignments: list[dict[str, Any]]  # per variant: field -> value
    scenes: list[Scene] | list[SheetScene]
    discrepancy: float | None = None  # centred L2 discrepancy of the random block's sample (sampling.discrepancy)

    @property
    def kind(self) -> str:
        """The body every variant is (:mod:`warpcloth.bodies`): ``"strip"`` or ``"sheet"``."""
        return bodies.of_scene(self.scenes[0]).name

    @property
    def strips(self) -> list[Scene]:
        """The variants of a sweep of strip scenes (none of a sweep of sheets)."""
        return [scene for scene in self.scenes if isinstance(scene, Scene)]

    @property
    def fingerprint(self) -> str:
        """Hash of every variant's resolved scene: identifies the sweep for resuming."""
        text = json.dumps([s.to_dict() for s in self.scenes], sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def batches(self, max_batch: int) -> list[list[int]]:
        """Variant indices per batch: grouped by batch-level fields, at most max_batch each."""
        if max_batch < 1:
            raise ArgumentError("max_batch", f"must be ≥ 1, got {max_batch}")
        batch_key = bodies.named(self.kind).hook("batch_key")
        groups: dict[str, list[int]] = {}
        for i, scene in enumerate(self.scenes):
            groups.setdefault(batch_key(scene), []).append(i)
        return [ids[j : j + max_batch] for ids in groups.values() for j in range(0, len(ids), max_batch)]


def _field_exists(resolved: dict, key: str) -> bool:
    node: Any = resolved
    try:
        parts = key_path(key)
    except SceneError:
        return False
    for part in parts:
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            return False
    return True


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(where, f"expected a finite number, got {value!r}")
    return float(value)


def _table(spec: dict, name: str) -> dict:
    table = spec.get(name, {})
    if not isinstance(table, dict):
        raise SceneError(f"sweep.{name}", f"expected a table of field = values, got {table!r}")
    return table


def _value_lists(table: dict, where: str) -> dict[str, list]:
    for key, values in table.items():
        if not isinstance(values, list) or not values:
            raise SceneError(f'{where}."{key}"', f"expected a non-empty list of values, got {values!r}")
    return table


def samples_latin_hypercube(spec: dict) -> bool:
    """Whether a raw [sweep] section draws a Latin hypercube (its variants then depend on
    the sampler's draws, not only on its seed)."""
    block = spec.get("random")
    return isinstance(block, dict) and bool(block) and block.get("method", "latin_hypercube") == "latin_hypercube"


@dataclass(frozen=True)
class RandomBlock:
    """A validated ``[sweep.random]`` block: its fields and how many samples, before any
    is drawn (so its size is checked in closed form first)."""

    keys: list[str]
    bounds: list[tuple[float, float]]
    samples: int
    method: str
    seed: int

    def sample(self) -> tuple[np.ndarray, np.ndarray]:
        """The seeded samples ``[sample, field]`` inside the bounds and the same sample in the
        unit box (one empty row and no box without a block)."""
        if not self.keys:
            return np.zeros((1, 0)), np.zeros((0, 0))
        generator = np.random.default_rng(self.seed)
        d = len(self.bounds)
        # latin_hypercube: one sample per stratum in every dimension, strata paired at random
        unit = (
            generator.random((self.samples, d))
            if self.method == "uniform"
            else latin_hypercube(self.samples, d, generator)
        )
        low = np.array([b[0] for b in self.bounds])
        high = np.array([b[1] for b in self.bounds])
        return low + unit * (high - low), unit


def _random_block(spec: dict) -> RandomBlock:
    block = _table(spec, "random")
    if not block:
        return RandomBlock([], [], 1, "uniform", 0)
    unknown = set(block) - RANDOM_KEYS
    if unknown:
        raise SceneError(
            f"sweep.random.{sorted(unknown)[0]}", f"unknown field; known: {', '.join(sorted(RANDOM_KEYS))}"
        )
    method = block.get("method", "latin_hypercube")
    if method not in METHODS:
        raise SceneError("sweep.random.method", f"must be one of {', '.join(METHODS)}; got {method!r}")
    samples = block.get("samples")
    if isinstance(samples, float) and samples.is_integer() and samples >= 1:
        samples = int(samples)  # 1e4, as TOML writes a large count in exponent form
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise SceneError("sweep.random.samples", f"expected a positive integer, got {samples!r}")
    ranges = block.get("ranges", {})
    if not isinstance(ranges, dict) or not ranges:
        raise SceneError("sweep.random.ranges", "expected a table of field = [low, high]")
    bounds = []
    for key, rng in ranges.items():
        where = f'sweep.random.ranges."{key}"'
        if not isinstance(rng, list) or len(rng) != 2:
            raise SceneError(where, f"expected [low, high], got {rng!r}")
        low, high = _number(rng[0], where), _number(rng[1], where)
        if not high > low:
            raise SceneError(where, f"high ({high:g}) must be above low ({low:g})")
        bounds.append((low, high))
    seed = spec.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise SceneError("sweep.seed", f"expected a non-negative integer, got {seed!r}")
    return RandomBlock(list(ranges), bounds, samples, method, seed)


def expand(raw: dict, max_variants: int = MAX_VARIANTS, progress: bool = False) -> Sweep:
    """Expand a raw scene with a ``[sweep]`` section into validated variant scenes.

    A sweep of more than ``max_variants`` variants is refused before it is expanded;
    ``progress`` shows a bar while a large one is.
    """
    checked_instance("raw", raw, dict, "warpcloth.scene.read_scene_file(name_or_path)")
    base = copy.deepcopy(raw)
    spec = base.pop("sweep", None)
    if not isinstance(spec, dict) or not (set(spec) & {"grid", "zip", "random"}):
        raise SceneError("sweep", "the scene has no [sweep] section with a grid, zip or random block")
    unknown = set(spec) - SWEEP_KEYS
    if unknown:
        raise SceneError(f"sweep.{sorted(unknown)[0]}", f"unknown field; known: {', '.join(sorted(SWEEP_KEYS))}")
    body = bodies.of_data(base)
    resolved = body("sweep_variant", copy.deepcopy(base)).to_dict()
    grid = _value_lists(_table(spec, "grid"), "sweep.grid")
    zipped = _value_lists(_table(spec, "zip"), "sweep.zip")
    lengths = {len(v) for v in zipped.values()}
    if len(lengths) > 1:
        raise SceneError("sweep.zip", f"lists must have equal lengths, got {sorted(lengths)}")
    random = _random_block(spec)
    random_keys = random.keys
    keys = list(grid) + list(zipped) + random_keys
    for where, block in (("sweep.grid", grid), ("sweep.zip", zipped), ("sweep.random.ranges", random_keys)):
        for key in block:
            if not _field_exists(resolved, key):
                raise SceneError(f'{where}."{key}"', "is not a scene field (dotted name, list items by index)")
    seen = set()
    for key in keys:
        if key in seen:
            raise SceneError(f'sweep."{key}"', "is swept in more than one block")
        seen.add(key)
    # Python integers, counted before anything is drawn or expanded
    n_variants = math.prod(len(v) for v in grid.values()) * max(lengths or {1}) * random.samples
    if n_variants > max_variants:
        raise ArgumentError(
            "max_variants",
            f"the sweep has {n_variants} variants, more than {max_variants}; each "
            "is a validated scene in memory (~1 ms and a few kB apiece): split it into several "
            "sweeps, or raise --max-variants (Python: max_variants=)",
        )
    check_memory(n_variants * VARIANT_BYTES, f"the sweep's {n_variants} variant scenes", "split it into several sweeps")
    grid_rows = list(itertools.product(*grid.values())) if grid else [()]
    zip_rows = list(zip(*zipped.values(), strict=True)) if zipped else [()]
    random_values, unit = random.sample()
    assignments = []
    for g, z, r in itertools.product(grid_rows, zip_rows, random_values):
        assignments.append(dict(zip(keys, [*g, *z, *(float(x) for x in r)], strict=True)))
    return Sweep(base, spec, keys, assignments, variant_scenes(base, assignments, progress), discrepancy(unit))


def variant_scenes(
    base: dict, assignments: list[dict[str, Any]], progress: bool = False
) -> list[Scene] | list[SheetScene]:
    """The validated scene of each variant: the raw ``base`` scene with the variant's
    fields set (``progress`` shows a bar); a refused one is a SceneError naming it."""
    body = bodies.of_data(base)
    scenes = []
    # leave=False: a refused variant's message then starts on a clean line
    with tqdm(
        total=len(assignments),
        desc="expanding sweep",
        unit=" variants",
        disable=not progress,
        dynamic_ncols=True,
        leave=False,
    ) as bar:
        for i, assignment in enumerate(assignments):
            data = copy.deepcopy(base)
            try:
                # A material file replaces the material, so it goes first and the other
                # swept material fields land on top of it, whatever their order in [sweep].
                for key, value in sorted(assignment.items(), key=lambda kv: not is_material_file_key(kv[0])):
                    set_field(data, key, value)
                scenes.append(body("sweep_variant", data))
            except SceneError as exc:
                raise variant_error(exc, i, assignment) from exc
            bar.update()
    return body("sweep_ready", scenes, assignments)


def load_sweep(
    name_or_path: str | Path,
    overrides: list[str] | tuple[str, ...] = (),
    max_variants: int = MAX_VARIANTS,
    progress: bool = False,
) -> Sweep:
    """Read a scene with a ``[sweep]`` section (path or bundled name) and expand it.

    ``overrides`` (``key=value``) change the base scene, e.g. ``run.duration_s=1``, or
    the sweep's own options: ``sweep.seed``, ``sweep.random.samples``, ``sweep.random.method``.
    ``max_variants`` and ``progress`` are :func:`expand`'s.
    """
    text, where = scene_source(name_or_path)
    raw = read_scene_file(name_or_path)
    spec = {"sweep": raw.pop("sweep", None) or {}}
    own = [o for o in overrides if o.split("=", 1)[0].strip().startswith("sweep.")]
    try:
        spec = apply_overrides(spec, own)
        overridden = apply_overrides(raw, [o for o in overrides if o not in own])
        bodies.of_overridden(raw, overridden, where)
        raw = overridden
        raw["sweep"] = spec["sweep"]
        sweep = expand(raw, max_variants, progress)
        swept = [key_path(k) for k in sweep.keys]
        # every strip variant's step, before any runs (a sheet's: checked as it was expanded)
        for i, scene in enumerate(sweep.strips):
            try:
                check_step(scene)
            except SceneError as exc:
                read = [key_path_or_none(f) for f in (exc.field, *exc.related)]
                if any(overlaps(k, f) for k in swept for f in read):
                    raise variant_error(exc, i, sweep.assignments[i]) from exc
                raise SceneError(exc.field, f"{exc.message} (the base scene: every variant)", exc.related) from exc
        return sweep
    except SceneError as exc:
        raise located(exc, text, where, overrides) from None
