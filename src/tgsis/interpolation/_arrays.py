"""Checked arrays shared by the interpolation modules: points, triangles, the interior vertices of a mesh.

Each check raises the error class its caller names (a projection or a
parameterisation error), so that messages name the operation that failed.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidInputError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def as_points(points: npt.ArrayLike, what: str, error: type[InvalidInputError]) -> FloatArray:
    """(n, 3) finite float64 points; ``error`` otherwise."""
    array = np.ascontiguousarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3:
        raise error(f"{what} must have shape (n, 3), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise error(f"{what} must be finite")
    return array


def as_triangles(triangles: npt.ArrayLike, n: int, what: str, error: type[InvalidInputError]) -> IntArray:
    """(m, 3) int64 triangles of distinct vertices among 0..n-1, m >= 1; ``error`` otherwise."""
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
        raise error(f"{what} must have shape (m, 3) with m >= 1, got {tri.shape}")
    if tri.min() < 0 or tri.max() >= n:
        raise error(f"{what} use a vertex index outside 0..{n - 1}")
    repeated = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 2] == tri[:, 0])
    if np.any(repeated):
        raise error(f"triangle {int(np.argmax(repeated))} uses one vertex twice")
    return tri


def interior_mask(triangles: IntArray, n: int) -> npt.NDArray[np.bool_]:
    """True for vertices not on the border (edges used by one triangle)."""
    a = triangles.ravel()
    b = triangles[:, [1, 2, 0]].ravel()
    low, high = np.minimum(a, b), np.maximum(a, b)
    keys, counts = np.unique(low * n + high, return_counts=True)
    single = keys[counts == 1]
    mask = np.ones(n, dtype=bool)
    mask[single // n] = False
    mask[single % n] = False
    return mask
