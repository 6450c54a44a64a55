"""Small meshes for the interpolation set-up tests (numpy only)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tgsis.mesh import Surface

IntArray = npt.NDArray[np.int64]


def grid_triangles(nx: int, ny: int) -> IntArray:
    """Triangles of an nx x ny vertex grid, vertex ``r * nx + c`` at (c, r), counter-clockwise seen from +z."""
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]).astype(np.int64)


def grid(nx: int, ny: int, *, wavy: bool = False) -> Surface:
    """An nx x ny vertex grid on the unit squares (z = 0, or a gentle wave), a disk."""
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    z = 0.3 * np.sin(x) * np.cos(0.7 * y) if wavy else np.zeros_like(x)
    return Surface(np.stack([x.ravel(), y.ravel(), z.ravel()], 1), grid_triangles(nx, ny), name="grid")


def vid(nx: int, col: int, row: int) -> int:
    """Index of the grid vertex at (col, row)."""
    return row * nx + col


def shuffled(surface: Surface, seed: int = 0) -> tuple[Surface, IntArray]:
    """The same surface with vertices renumbered and triangles reordered; returns it and old -> new."""
    rng = np.random.default_rng(seed)
    new_of_old = rng.permutation(surface.n_vertices).astype(np.int64)
    vertices = np.empty_like(surface.vertices)
    vertices[new_of_old] = surface.vertices
    triangles = new_of_old[surface.triangles][rng.permutation(surface.n_cells)]
    # rotate the corners of each triangle too (same orientation)
    shift = rng.integers(0, 3, len(triangles))
    rows = np.arange(len(triangles))[:, None]
    triangles = triangles[rows, (np.arange(3)[None, :] + shift[:, None]) % 3]
    return Surface(vertices, triangles), new_of_old


def delaunay_disk(n: int, seed: int = 1) -> Surface:
    """An irregular disk: Delaunay triangles of random points in the unit disk, oriented counter-clockwise."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    angle = rng.uniform(0, 2 * np.pi, n)
    radius = np.sqrt(rng.uniform(0, 1, n))
    xy = np.stack([radius * np.cos(angle), radius * np.sin(angle)], 1)
    tri = Delaunay(xy).simplices.astype(np.int64)
    p = xy[tri]
    u, w = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
    tri[area < 0] = tri[area < 0][:, [0, 2, 1]]
    return Surface(np.column_stack([xy, 0.1 * xy[:, 0] ** 2]), tri, name="delaunay")


def annulus(nx: int = 6, ny: int = 6) -> Surface:
    """A grid with the triangles of its centre square removed: two border loops."""
    s = grid(nx, ny)
    cx, cy = nx // 2 - 1, ny // 2 - 1
    square = {vid(nx, cx, cy), vid(nx, cx + 1, cy), vid(nx, cx, cy + 1), vid(nx, cx + 1, cy + 1)}
    keep = [i for i, t in enumerate(s.triangles.tolist()) if not set(t) <= square]
    return Surface(s.vertices, s.triangles[keep], name="annulus")


def torus(nu: int = 6, nv: int = 5) -> Surface:
    """A closed torus, a periodic nu x nv grid, oriented consistently."""
    uu, vv = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv)
    u, v = uu.ravel(), vv.ravel()
    vertices = np.stack([(3 + np.cos(v)) * np.cos(u), (3 + np.cos(v)) * np.sin(u), np.sin(v)], 1)
    idx = np.arange(nu * nv).reshape(nv, nu)
    a = idx
    b = np.roll(idx, -1, axis=1)
    c = np.roll(idx, -1, axis=0)
    d = np.roll(b, -1, axis=0)
    tri = np.concatenate(
        [np.stack([a.ravel(), b.ravel(), d.ravel()], 1), np.stack([a.ravel(), d.ravel(), c.ravel()], 1)]
    )
    return Surface(vertices, tri, name="torus")


def mobius(n: int = 8) -> Surface:
    """A Möbius strip of n squares: non-orientable, so some edge is run the same way by its two triangles."""
    t = np.arange(n) * 2 * np.pi / n
    half = t / 2
    inner = np.stack(
        [(2 - 0.5 * np.cos(half)) * np.cos(t), (2 - 0.5 * np.cos(half)) * np.sin(t), -0.5 * np.sin(half)], 1
    )
    outer = np.stack(
        [(2 + 0.5 * np.cos(half)) * np.cos(t), (2 + 0.5 * np.cos(half)) * np.sin(t), 0.5 * np.sin(half)], 1
    )
    vertices = np.concatenate([inner, outer])
    tris = []
    for i in range(n):
        a, b = i, n + i
        if i < n - 1:
            c, d = i + 1, n + i + 1
        else:  # the twist: inner meets outer
            c, d = n, 0
        tris += [[a, c, d], [a, d, b]]
    return Surface(vertices, tris, name="mobius")


def brute_edges(triangles: npt.ArrayLike) -> set[tuple[int, int]]:
    """Undirected edges by a plain Python loop (reference for the vectorised code)."""
    out: set[tuple[int, int]] = set()
    for a, b, c in np.asarray(triangles).tolist():
        for p, q in ((a, b), (b, c), (c, a)):
            out.add((min(p, q), max(p, q)))
    return out


def brute_border(triangles: npt.ArrayLike) -> set[tuple[int, int]]:
    """Directed border edges (as the triangle runs them) by a plain Python loop."""
    count: dict[tuple[int, int], int] = {}
    directed: dict[tuple[int, int], tuple[int, int]] = {}
    for a, b, c in np.asarray(triangles).tolist():
        for p, q in ((a, b), (b, c), (c, a)):
            key = (min(p, q), max(p, q))
            count[key] = count.get(key, 0) + 1
            directed[key] = (p, q)
    return {directed[k] for k, v in count.items() if v == 1}


def signed_area(vertices: npt.ArrayLike, loop: npt.ArrayLike) -> float:
    """Signed area of a closed polygon in the xy plane (positive: counter-clockwise)."""
    p = np.asarray(vertices)[np.asarray(loop)][:, :2]
    q = np.roll(p, -1, axis=0)
    return float(0.5 * np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))
