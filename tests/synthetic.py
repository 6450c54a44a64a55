"""Small synthetic meshes the tests share."""

from __future__ import annotations

import numpy as np

import tgsis


def flat_grid(side: int, z: float) -> tgsis.Surface:
    """A side x side grid of unit squares at height z, two triangles each, named ``z<z>``."""
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.full(side * side, z)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]), name=f"z{z}")
