"""Reference tables generated from the code when the documentation is built.

``scene-fields``: every field of :class:`warpcloth.scene.Scene` becomes a row (dotted name, TOML type,
default, constraints, whether it may differ between the strips of one batch, and the
one-line description the schema carries in its metadata), one table per ``[section]``.
The tables are built from the same dataclasses the scene parser validates against, so
the reference cannot drift from the code.

``probe-columns``: the probe columns of a run (``warpcloth.kernels.PROBE_FIELDS``) with
their units; a probe without a description here, or a description of a probe that no
longer exists, is a build warning (an error under ``-W``).
"""

from __future__ import annotations

import dataclasses
import typing

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

HEADERS = ("field", "type", "default", "allowed", "per strip", "meaning")
WIDTHS = (24, 10, 12, 12, 6, 36)


def _toml(value: object) -> str:
    """A default as it would be written in a scene file."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return f"{value:g}" if isinstance(value, float) else str(value)


def _type_name(tp: object) -> str:
    """The TOML type of a field's Python type."""
    origin = typing.get_origin(tp)
    if origin is list:
        (item,) = typing.get_args(tp)
        return "array of tables" if dataclasses.is_dataclass(item) else f"array of {_type_name(item)}"
    return {float: "float", int: "integer", str: "string", bool: "boolean"}.get(tp, getattr(tp, "__name__", str(tp)))


def _default(f: dataclasses.Field) -> object:
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default


def _allowed(meta: dict) -> str:
    if meta.get("choices"):
        return " | ".join(meta["choices"])
    if meta.get("gt") is not None:
        return f"> {meta['gt']:g}"
    if meta.get("ge") is not None:
        return f"≥ {meta['ge']:g}"
    return ""


def field_rows(section_type: type, prefix: str) -> list[tuple[str, ...]]:
    """One row per field of a schema dataclass (nested tables such as clamp segments
    get rows of their own, ``clamp.segments[].t_start_s``)."""
    rows = []
    hints = typing.get_type_hints(section_type)
    for f in dataclasses.fields(section_type):
        meta, tp = f.metadata, hints[f.name]
        rows.append(
            (
                f"{prefix}.{f.name}",
                _type_name(tp),
                _toml(_default(f)),
                _allowed(meta),
                "yes" if meta.get("per_strip") else "",
                meta.get("doc", ""),
            )
        )
        item = typing.get_args(tp)[0] if typing.get_origin(tp) is list else None
        if item is not None and dataclasses.is_dataclass(item):
            rows += field_rows(item, f"{prefix}.{f.name}[]")
    return rows


def _entry(text: str, literal: bool = False) -> nodes.entry:
    para = nodes.paragraph()
    if text:
        para += nodes.literal(text, text) if literal else nodes.Text(text)
    entry = nodes.entry()
    entry += para
    return entry


def _table(
    title: str,
    rows: list[tuple[str, ...]],
    headers: tuple[str, ...] = HEADERS,
    widths: tuple[int, ...] = WIDTHS,
    literal: tuple[int, ...] = (0, 2),
) -> nodes.table:
    table = nodes.table(classes=["generated-reference"])
    table += nodes.title(title, title)
    group = nodes.tgroup(cols=len(headers))
    table += group
    for width in widths:
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    header = nodes.row()
    for name in headers:
        header += _entry(name)
    head += header
    group += head
    body = nodes.tbody()
    for row in rows:
        line = nodes.row()
        for k, cell in enumerate(row):
            line += _entry(cell, literal=k in literal)
        body += line
    group += body
    return table


class SceneFields(SphinxDirective):
    """``.. scene-fields::`` — every scene section as a table of its fields."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        """Build the tables from :class:`warpcloth.scene.Scene`."""
        from warpcloth.scene import Scene

        tables: list[nodes.Node] = []
        for section, section_type in typing.get_type_hints(Scene).items():
            summary = " ".join((section_type.__doc__ or "").split())
            tables.append(_table(f"[{section}] — {summary}", field_rows(section_type, section)))
        return tables


PROBE_MEANINGS = {
    "tip_x": "x of the free end",
    "tip_y": "y of the free end",
    "tip_speed": "speed of the free end",
    "laser_x": "x where the strip crosses the laser line (first crossing from the clamp down)",
    "clamp_angle": "clamp rotation θ (counter-clockwise +)",
    "kinetic": "kinetic energy of the free nodes",
    "gravitational": "gravitational energy of the free nodes",
    "tensile": "tensile (stretch) energy",
    "bending_elastic_work": "work against the elastic part D K of the bending moments, from t = 0",
    "hysteresis_work": "work dissipated by the hysteretic part of the bending moments, from t = 0",
    "damping_work": "work dissipated by damping, from t = 0",
    "drive_work": "work done by the drives (the clamp, the held free end), from t = 0",
    "loop_curvature": "curvature of the probed hinge",
    "loop_moment": "bending moment per width of the probed hinge",
}
"""What each probe column holds (units come from ``PROBE_UNITS``)."""


class ProbeColumns(SphinxDirective):
    """``.. probe-columns::`` — the probe columns of probes.csv with units and meanings."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        """Build the table from ``PROBE_FIELDS`` and ``PROBE_UNITS``."""
        from warpcloth.kernels import PROBE_FIELDS, PROBE_UNITS

        for name in sorted(set(PROBE_FIELDS) ^ set(PROBE_MEANINGS)):
            where = (
                "has no description in docs/_ext/scene_reference.py"
                if name in PROBE_FIELDS
                else "is described in docs/_ext/scene_reference.py but is not a probe"
            )
            logger.warning(f"probe column {name!r} {where}", location=self.get_location())
        rows = [(name, PROBE_UNITS[name], PROBE_MEANINGS.get(name, "")) for name in PROBE_FIELDS]
        return [_table("probe columns", rows, ("column", "unit (SI)", "meaning"), (16, 22, 50), (0,))]


def setup(app: Sphinx) -> dict:
    """Register the directives."""
    app.add_directive("scene-fields", SceneFields)
    app.add_directive("probe-columns", ProbeColumns)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
