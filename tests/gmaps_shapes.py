"""Meshes whose topology is known: closed and bordered surfaces, a non-orientable strip, solids."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def octahedron() -> tuple[FloatArray, IntArray]:
    """A sphere: 6 vertices, 12 edges, 8 triangles (chi = 2), orientations mixed on purpose."""
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    t = np.array(
        [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [5, 3, 1], [0, 3, 5]], dtype=np.int64
    )
    return v, t


def icosahedron() -> tuple[FloatArray, IntArray]:
    """A sphere: 12 vertices, 30 edges, 20 triangles."""
    p = (1 + 5**0.5) / 2
    v = np.array(
        [
            [-1, p, 0],
            [1, p, 0],
            [-1, -p, 0],
            [1, -p, 0],
            [0, -1, p],
            [0, 1, p],
            [0, -1, -p],
            [0, 1, -p],
            [p, 0, -1],
            [p, 0, 1],
            [-p, 0, -1],
            [-p, 0, 1],
        ],
        dtype=float,
    )
    t = np.array(
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ],
        dtype=np.int64,
    )
    return v, t


def grid(
    nx: int, ny: int, *, wrap_x: bool = False, wrap_y: bool = False, twist: bool = False
) -> tuple[FloatArray, IntArray]:
    """A triangulated nx x ny grid of the unit square, optionally glued: x (cylinder), x and y (torus).

    ``twist`` glues the x ends with y reversed (a Möbius strip). Coordinates are
    the grid's (u, v, 0); gluing only reuses vertex indices.
    """
    cols = nx if wrap_x else nx + 1
    rows = ny if wrap_y else ny + 1
    u, w = np.meshgrid(np.arange(cols) / nx, np.arange(rows) / ny, indexing="ij")
    v = np.stack([u.ravel(), w.ravel(), np.zeros(u.size)], axis=1)

    def vid(i: IntArray, j: IntArray) -> IntArray:
        wrapped = i >= cols
        i = np.where(wrapped, i - cols, i)
        if twist:
            j = np.where(wrapped, ny - j, j)
        j = j % rows if wrap_y else j
        return i * rows + j

    i2, j2 = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    i, j = i2.ravel(), j2.ravel()
    a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
    t = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]).astype(np.int64)
    return v, t


def cube_tetrahedra() -> tuple[FloatArray, IntArray]:
    """The unit cube split into 5 tetrahedra (a ball: chi = 1, border a sphere)."""
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    # corners: index = 4x + 2y + z
    t = np.array([[0, 3, 5, 6], [0, 1, 3, 5], [0, 2, 3, 6], [0, 4, 5, 6], [3, 5, 6, 7]], dtype=np.int64)
    return v, t


def block_tetrahedra(n: int) -> tuple[FloatArray, IntArray]:
    """An n x n x n block of cubes, each split into 6 tetrahedra around its main diagonal."""
    m = n + 1
    x, y, z = np.meshgrid(np.arange(m), np.arange(m), np.arange(m), indexing="ij")
    v = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1).astype(float)
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij"))

    def vid(di: int, dj: int, dk: int) -> IntArray:
        return ((i + di) * m + (j + dj)) * m + (k + dk)

    c = [vid(a, b, d) for a in (0, 1) for b in (0, 1) for d in (0, 1)]  # corner 4a + 2b + d
    paths = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
    t = np.concatenate([np.stack([c[p] for p in path], axis=1) for path in paths]).astype(np.int64)
    return v, t
