"""Signed distance volumes on a regular grid."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Tuple

import numpy as np


@dataclass
class Volume:
    """Values on a regular grid placed in the world.

    ``values`` is a 3D float array indexed ``[k, j, i]`` (z, y, x: x varies
    fastest in memory, the layout of isomorph's ``.npy`` volumes); the node
    ``(i, j, k)`` lies at ``origin + spacing * (i, j, k)`` (world units,
    cubic voxels).

    As an input: with ``iso=None`` the values are signed distances, positive
    inside and zero on the surface; with ``iso`` given they are any values
    (a density, a scaled field) whose surface is the level ``iso``, larger
    inside, and are redistanced. ``Morph.frame_volume`` returns a
    ``Volume`` (the frame's field minus its iso value, positive inside).
    ``np.asarray(volume)`` gives ``values``.
    """

    values: np.ndarray
    origin: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    spacing: float = 1.0
    iso: Optional[float] = None

    def __post_init__(self) -> None:
        self.values = np.asarray(self.values)
        if self.values.ndim != 3:
            raise ValueError(f"Volume values must be a 3D array indexed [k, j, i], got shape {self.values.shape}")
        self.origin = tuple(float(x) for x in self.origin)  # type: ignore[assignment]
        if len(self.origin) != 3:
            raise ValueError("Volume origin must be three numbers (x, y, z)")
        self.spacing = float(self.spacing)

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        return self.values if dtype is None else self.values.astype(dtype)

    @property
    def shape(self) -> Tuple[int, int, int]:
        """The values' shape ``(nz, ny, nx)``."""
        return self.values.shape  # type: ignore[return-value]

    def positions(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The world coordinates of the nodes along x, y and z (1D arrays)."""
        nz, ny, nx = self.values.shape
        o, h = self.origin, self.spacing
        return (o[0] + h * np.arange(nx), o[1] + h * np.arange(ny), o[2] + h * np.arange(nz))
