"""What a batch of strips *is*: geometry and material, as Warp arrays (SI)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import warp as wp

from warpcloth.kernels import KernelSet, build_kernels

from . import units
from .errors import SceneError
from .material import to_si
from .scene import Scene, batch_fields

PRECISIONS = {"float64": wp.float64, "float32": wp.float32}


def check_batch(scenes: Sequence[Scene]) -> None:
    """Raise SceneError unless every batch-level field agrees across ``scenes``."""
    if not scenes:
        raise SceneError("scenes", "a batch needs at least one scene")
    first = scenes[0].to_dict()
    for i, scene in enumerate(scenes[1:], start=1):
        other = scene.to_dict()
        for name in batch_fields():
            section, key = name.split(".")
            if first[section][key] != other[section][key]:
                raise SceneError(name, f"differs between variant 0 ({first[section][key]!r}) and variant {i} "
                                 f"({other[section][key]!r}); it cannot vary within one batch")


def rest_positions(scene: Scene) -> np.ndarray:
    """Straight hanging strip: node i at (0, −i h), the clamp's top at the origin."""
    return np.stack([np.zeros(scene.n_nodes), -scene.spacing * np.arange(scene.n_nodes)], axis=-1)


def clamp_edge(scene: Scene) -> np.ndarray:
    """The clamp's lowest point (origin of rotation-centre, hold and laser offsets)."""
    return np.array([0.0, -scene.strip.clamp_length_mm * units.LENGTH_MM])


class Model:
    """Static description of B strips sharing node count, spacing and time step.

    Every material parameter, width and damping may differ per strip.
    """

    def __init__(self, scenes: Sequence[Scene], device: str | None = None) -> None:
        check_batch(scenes)
        self.scenes = list(scenes)
        first = self.scenes[0]
        self.device = wp.get_device(device)
        self.kernels: KernelSet = build_kernels(PRECISIONS[first.integrator.precision])
        self.n_strips = len(self.scenes)
        self.n_nodes = first.n_nodes
        self.n_clamped = first.n_clamped
        self.spacing = first.spacing
        self.gravity = first.run.gravity_m_per_s2
        materials = [to_si(s.material) for s in self.scenes]
        self.width = np.array([s.strip.width_mm * units.LENGTH_MM for s in self.scenes])
        self.density = np.array([m.density for m in materials])
        self.node_mass = self.density * self.width * self.spacing
        self.tensile = np.array([m.tensile for m in materials])
        self.bending_rigidity = np.array([m.bending_rigidity for m in materials])
        self.hysteresis_d1 = np.array([m.hysteresis_d1 for m in materials])
        self.hysteresis_alpha = np.array([m.hysteresis_alpha for m in materials])
        self.hysteresis_k0 = np.array([m.hysteresis_k0 for m in materials])
        self.hysteresis_m0 = np.array([m.hysteresis_m0 for m in materials])
        self.damping = np.array([s.damping.gamma_per_s for s in self.scenes])
        self.struct = self._build_struct()

    def array(self, values: np.ndarray, dtype: object = None) -> wp.array:
        """A Warp array of ``values`` on this model's device in its precision."""
        return wp.array(np.ascontiguousarray(values), dtype=dtype or self.kernels.scalar, device=self.device)

    def _build_struct(self) -> object:
        k = self.kernels
        m = k.StripModel()
        m.n_nodes = self.n_nodes
        m.n_clamped = self.n_clamped
        m.rest_length = k.scalar(self.spacing)
        m.gravity = k.scalar(self.gravity)
        m.tensile = self.array(self.tensile, k.vec4)
        m.bending_rigidity = self.array(self.bending_rigidity)
        m.hysteresis_d1 = self.array(self.hysteresis_d1)
        m.hysteresis_alpha = self.array(self.hysteresis_alpha)
        m.hysteresis_k0 = self.array(self.hysteresis_k0)
        m.hysteresis_m0 = self.array(self.hysteresis_m0)
        m.width = self.array(self.width)
        m.node_mass = self.array(self.node_mass)
        m.damping = self.array(self.damping)
        return m
