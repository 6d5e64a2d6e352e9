"""Scenes: the schema, parsing, ``--set`` overrides, validation, materials, sweeps, and
:func:`build_batch`, the one step from scenes to simulation objects (SI)."""

from .build import Batch, build_batch, builder_for, check_batch
from .files import bundled_scenes, load_scene, read_scene_file, scene_from_dict, strip_scene_from_dict
from .geometry import COORDINATES, rest_positions
from .materials import (
    MATERIAL_FILE_KEY,
    bundled_materials,
    field_laws,
    hysteresis_amplitudes,
    law_aliases,
    law_fields,
    material_fields,
    material_shear,
    read_material_file,
    tensile_slope_minimum,
    to_si,
    validate_material,
)
from .overrides import apply_overrides, set_field
from .schema import (
    DEFAULT_MATERIAL,
    DEFAULT_MATERIAL_NAME,
    ClampSection,
    IntegratorSection,
    MaterialSection,
    Scene,
    batch_fields,
    choice_fields,
)
from .shear import RIGIDITY_FIELD, ShearMaterial, parse_shear, shear_field, shear_fields, shear_parameters, shear_unit
from .step import check_step
from .sweep import Sweep, expand, load_sweep

__all__ = [
    "COORDINATES",
    "DEFAULT_MATERIAL",
    "DEFAULT_MATERIAL_NAME",
    "MATERIAL_FILE_KEY",
    "Batch",
    "ClampSection",
    "IntegratorSection",
    "MaterialSection",
    "Scene",
    "Sweep",
    "apply_overrides",
    "batch_fields",
    "choice_fields",
    "build_batch",
    "builder_for",
    "bundled_materials",
    "bundled_scenes",
    "check_batch",
    "check_step",
    "expand",
    "load_scene",
    "load_sweep",
    "field_laws",
    "hysteresis_amplitudes",
    "law_aliases",
    "law_fields",
    "material_fields",
    "material_shear",
    "RIGIDITY_FIELD",
    "ShearMaterial",
    "parse_shear",
    "shear_field",
    "shear_fields",
    "shear_parameters",
    "shear_unit",
    "read_material_file",
    "read_scene_file",
    "rest_positions",
    "scene_from_dict",
    "set_field",
    "strip_scene_from_dict",
    "tensile_slope_minimum",
    "to_si",
    "validate_material",
]
