"""Builders: n-G-maps from simplices (points, segments, triangles, tetrahedra, any n) and from polygons.

They return the parts of a map (:class:`Parts`); :mod:`tgsis.gmaps._core` makes the
:class:`~tgsis.gmaps.GMap` of them, so that this module does not import the class that calls it.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGeometryError, InvalidGMapError
from tgsis.gmaps._arrays import FloatArray, IntArray
from tgsis.gmaps._arrays import as_points as _as_points

if TYPE_CHECKING:
    from tgsis.mesh import Mesh


class Parts(NamedTuple):
    """What a builder makes: the arguments of :class:`~tgsis.gmaps.GMap` (its module builds the map from them)."""

    alpha: IntArray
    vertex: IntArray
    points: FloatArray
    cell_properties: dict[int, Mapping[str, npt.ArrayLike]] | None


_CELL_NAMES = {1: "point", 2: "segment", 3: "triangle", 4: "tetrahedron"}
_FACET_NAMES = {1: "vertex", 2: "edge", 3: "face"}


def _plural(word: str, count: int | None = None) -> str:
    many = {"tetrahedron": "tetrahedra", "vertex": "vertices"}.get(word, word + "s")
    return many if count is None else f"{count} {word if count == 1 else many}"


def _cell_name(size: int) -> str:
    return _CELL_NAMES.get(size, f"{size - 1}-simplex")


def _vertices(vertices: npt.ArrayLike) -> npt.NDArray[np.float64]:
    try:
        return _as_points(vertices, "vertices", "vertex")
    except InvalidGMapError as exc:
        raise InvalidGeometryError(exc.message, detail=exc.detail) from None


def _indices(values: npt.ArrayLike, what: str, n_vertices: int, ndim: int) -> IntArray:
    raw = np.asarray(values)
    if raw.size == 0:
        return np.empty((0,) * ndim if ndim == 1 else (0, raw.shape[1] if raw.ndim == 2 else 0), dtype=np.int64)
    if raw.dtype.kind not in "iu":
        raise InvalidGeometryError(f"{what} must be integer vertex indices, got {raw.dtype}")
    if raw.ndim != ndim:
        raise InvalidGeometryError(f"{what} must be a {ndim}-D array of vertex indices, got shape {raw.shape}")
    array = np.ascontiguousarray(raw, dtype=np.int64)
    outside = (array < 0) | (array >= n_vertices)
    if outside.any():
        where = tuple(int(v) for v in np.argwhere(outside)[0])
        raise InvalidGeometryError(
            f"{what}{list(where)} refers to vertex {array[where]}, but there are {n_vertices} vertices",
            detail=f"{int(outside.sum())} indices are out of range",
        )
    return array


def _pair_rows(rows: IntArray, base: int) -> tuple[IntArray, IntArray]:
    """Pair equal rows of a (q, w) array of sorted vertex indices in 0..base-1.

    Returns
    -------
    partner : (q,) int64
        The other row with the same vertices, or -1 for a row that no other has.
    crowded : (r,) int64
        Rows (one per group) shared by three or more.
    """
    q, w = rows.shape
    if q == 0:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    if w == 0:
        order = np.arange(q)
        same = np.ones(q - 1, dtype=bool)
    else:
        if float(base) ** w < 2.0**62:
            key = rows[:, 0].copy()
            for col in range(1, w):
                key *= base
                key += rows[:, col]
            order = np.argsort(key)
            sorted_key = key[order]
            same = sorted_key[1:] == sorted_key[:-1]
        else:
            order = np.lexsort(rows.T[::-1])
            ordered = rows[order]
            same = (ordered[1:] == ordered[:-1]).all(axis=1)
    starts = np.flatnonzero(np.concatenate([[True], ~same]))
    sizes = np.diff(np.concatenate([starts, [q]]))
    partner = np.full(q, -1, dtype=np.int64)
    two = starts[sizes == 2]
    partner[order[two]] = order[two + 1]
    partner[order[two + 1]] = order[two]
    return partner, order[starts[sizes > 2]].astype(np.int64)


def _sort_rows(rows: IntArray) -> IntArray:
    """Sort each row of a (q, w) array (sorting networks for w <= 3, faster than np.sort there)."""
    w = rows.shape[1]
    if w == 1:
        return rows.copy()
    if w == 2:
        return np.stack([np.minimum(rows[:, 0], rows[:, 1]), np.maximum(rows[:, 0], rows[:, 1])], axis=1)
    if w == 3:
        a, b, c = rows[:, 0], rows[:, 1], rows[:, 2]
        a, b = np.minimum(a, b), np.maximum(a, b)
        b, c = np.minimum(b, c), np.maximum(b, c)
        a, b = np.minimum(a, b), np.maximum(a, b)
        return np.stack([a, b, c], axis=1)
    return np.sort(rows, axis=1)


def _level_properties(
    props: Mapping[str, npt.ArrayLike] | None, level: int
) -> dict[int, Mapping[str, npt.ArrayLike]] | None:
    return {level: props} if props else None


def simplices_parts(
    vertices: npt.ArrayLike,
    simplices: npt.ArrayLike,
    *,
    cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    size: int | None = None,
) -> Parts:
    """The parts of :func:`tgsis.gmaps.from_simplices` (see it): darts, involutions, embedding."""
    points = _vertices(vertices)
    raw = np.asarray(simplices)
    if size is not None and (raw.ndim != 2 or raw.shape[1] != size) and raw.size:
        raise InvalidGeometryError(
            f"{_plural(_cell_name(size))} must be a (c, {size}) array of vertex indices, got shape {raw.shape}"
        )
    if raw.size == 0:
        s = size if size is not None else (raw.shape[1] if raw.ndim == 2 else 1)
        cells = np.empty((0, s), dtype=np.int64)
    else:
        cells = _indices(raw, _plural(_cell_name(raw.shape[1] if raw.ndim == 2 else 1)), len(points), 2)
    c, s = cells.shape
    if s == 0:
        raise InvalidGeometryError("simplices need at least one vertex each")
    n = s - 1
    name = _cell_name(s)
    pairs = list(itertools.combinations(range(s), 2))
    if pairs:
        repeated = np.zeros(c, dtype=bool)
        for u, w in pairs:
            repeated |= cells[:, u] == cells[:, w]
        if repeated.any():
            row = int(np.flatnonzero(repeated)[0])
            raise InvalidGeometryError(
                f"{name} {row} uses a vertex twice: {cells[row].tolist()}",
                detail=f"{_plural(name, int(repeated.sum()))} repeat a vertex index",
            )
    perms = np.array(list(itertools.permutations(range(s))), dtype=np.int64)
    nf = len(perms)  # (n + 1)!
    d = c * nf
    index_of = {tuple(p): j for j, p in enumerate(perms.tolist())}
    alpha = np.empty((n + 1, d), dtype=np.int64)
    base = (np.arange(c, dtype=np.int64) * nf)[:, None]
    for i in range(n):
        swapped = perms.copy()
        swapped[:, [i, i + 1]] = swapped[:, [i + 1, i]]
        local = np.array([index_of[tuple(p)] for p in swapped.tolist()], dtype=np.int64)
        np.add(base, local[None, :], out=alpha[i].reshape(c, nf))
    darts = np.arange(d, dtype=np.int64)
    top = alpha[n]
    top[:] = darts
    if n >= 1:
        # facet f of simplex t (opposite local vertex f): its sorted global vertices
        facets = np.empty((c, s, n), dtype=np.int64)
        for f in range(s):
            facets[:, f, :] = _sort_rows(np.delete(cells, f, axis=1))
        flat = facets.reshape(c * s, n)
        partner, crowded = _pair_rows(flat, len(points))
        if len(crowded):
            first = int(crowded[0])
            shared = flat[first]
            users = np.flatnonzero((facets == shared).all(axis=2).any(axis=1))
            what = _FACET_NAMES.get(n, f"{n - 1}-face")
            raise InvalidGeometryError(
                f"{what} {shared.tolist()} is shared by {_plural(name, len(users))} ({users[:10].tolist()}): "
                f"a G-map needs at most two {_plural(name)} per {what} (a quasi-manifold)",
                detail=f"{_plural(what, len(crowded))} shared by three or more {_plural(name)}",
            )
        # Each dart gets a code 0..n!-1: the order of its facet's global vertices, the same in both
        # simplices of a facet. It depends only on the dart's permutation and on the order of the
        # simplex's global vertices (one of (n + 1)!, read from its pairwise comparisons): a small table.
        pattern = np.zeros(c, dtype=np.int64)
        for bit, (u, w) in enumerate(pairs):
            pattern |= (cells[:, u] < cells[:, w]).astype(np.int64) << bit
        order_of_pattern = np.zeros(1 << len(pairs), dtype=np.int64)
        table_code = np.zeros((nf, nf), dtype=np.int64)
        lut = np.zeros(n**n, dtype=np.int64)
        powers = n ** np.arange(n, dtype=np.int64)
        for j, p in enumerate(itertools.permutations(range(n))):
            lut[int(np.dot(p, powers))] = j
        for o, ranks in enumerate(perms):  # ranks[u]: the place of local vertex u among the simplex's vertices
            order_of_pattern[sum(int(ranks[u] < ranks[w]) << bit for bit, (u, w) in enumerate(pairs))] = o
            seen = ranks[perms[:, :n]]  # (nf, n): the places of each dart's facet vertices, in dart order
            within = np.argsort(np.argsort(seen, axis=1), axis=1)
            table_code[o] = lut[within @ powers]
        pattern = order_of_pattern[pattern]
        code = table_code[pattern].reshape(d)
        facet_of = (np.arange(c, dtype=np.int64)[:, None] * s + perms[None, :, n]).reshape(d)
        nfac = nf // s  # n!
        slot = facet_of * nfac + code
        table = np.empty(d, dtype=np.int64)
        table[slot] = darts
        other = partner[facet_of]
        sewn = np.flatnonzero(other >= 0)
        top[sewn] = table[other[sewn] * nfac + code[sewn]]
    vertex = np.repeat(cells, nf // s, axis=1).reshape(d)  # perms[:, 0] is 0, 0, ..., 1, 1, ...
    return Parts(alpha, vertex, points, _level_properties(cell_properties, n))


def polygons_parts(
    vertices: npt.ArrayLike,
    polygons: npt.ArrayLike,
    offsets: npt.ArrayLike | None = None,
    *,
    cell_properties: Mapping[str, npt.ArrayLike] | None = None,
) -> Parts:
    """The parts of :func:`tgsis.gmaps.from_polygons` (see it): darts, involutions, embedding."""
    points = _vertices(vertices)
    k = len(points)
    if offsets is None:
        grid = np.asarray(polygons)
        if grid.size == 0:
            grid = np.empty((0, 3), dtype=np.int64)
        if grid.ndim != 2:
            raise InvalidGeometryError(
                f"polygons without offsets must be an (f, s) array, got shape {grid.shape}",
                hint="pass a flat index array and offsets for polygons of several sizes",
            )
        flat = _indices(grid.reshape(-1), "polygons", k, 1)
        offs = np.arange(grid.shape[0] + 1, dtype=np.int64) * grid.shape[1]
    else:
        flat = _indices(polygons, "polygons", k, 1)
        offs_raw = np.asarray(offsets)
        if offs_raw.dtype.kind not in "iu" or offs_raw.ndim != 1 or len(offs_raw) == 0:
            raise InvalidGeometryError(
                f"offsets must be a 1-D integer array of f + 1 positions, "
                f"got {offs_raw.dtype} of shape {offs_raw.shape}"
            )
        offs = offs_raw.astype(np.int64)
        if offs[0] != 0 or offs[-1] != len(flat):
            raise InvalidGeometryError(
                f"offsets must start at 0 and end at len(polygons) = {len(flat)}, got {int(offs[0])} .. {int(offs[-1])}"
            )
    sizes = np.diff(offs)
    small = np.flatnonzero(sizes < 3)
    if len(small):
        j = int(small[0])
        raise InvalidGeometryError(
            f"polygon {j} has {int(sizes[j])} corners: a polygon needs at least 3",
            detail=f"{len(small)} polygons have fewer than 3 corners",
        )
    f = len(sizes)
    face = np.repeat(np.arange(f, dtype=np.int64), sizes)
    if len(flat):
        pair = np.sort(face * k + flat)
        twice = np.flatnonzero(pair[1:] == pair[:-1])
        if len(twice):
            j = int(pair[twice[0]] // k)
            raise InvalidGeometryError(
                f"polygon {j} uses vertex {int(pair[twice[0]] % k)} twice: {flat[offs[j] : offs[j + 1]].tolist()}"
            )
    q = len(flat)
    corners = np.arange(q, dtype=np.int64)
    nxt = corners + 1
    nxt[offs[1:] - 1] = offs[:-1]
    a = flat
    b = flat[nxt]
    d = 2 * q
    alpha0 = np.arange(d, dtype=np.int64) ^ 1
    alpha1 = np.empty(d, dtype=np.int64)
    alpha1[2 * corners + 1] = 2 * nxt
    alpha1[2 * nxt] = 2 * corners + 1
    edges = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)
    partner, crowded = _pair_rows(edges, k)
    if len(crowded):
        shared = edges[int(crowded[0])]
        users = np.unique(face[(edges == shared).all(axis=1)])
        raise InvalidGeometryError(
            f"edge {shared.tolist()} is shared by {len(users)} polygons ({users[:10].tolist()}): "
            f"a G-map needs at most two polygons per edge (a quasi-manifold)",
            detail=f"{_plural('edge', len(crowded))} shared by three or more polygons",
        )
    low = 2 * corners + (a > b)  # the dart of each side at its lower-numbered vertex
    high = low ^ 1
    alpha2 = np.arange(d, dtype=np.int64)
    sewn = partner >= 0
    alpha2[low[sewn]] = low[partner[sewn]]
    alpha2[high[sewn]] = high[partner[sewn]]
    vertex = np.stack([a, b], axis=1).ravel()
    return Parts(np.stack([alpha0, alpha1, alpha2]), vertex, points, _level_properties(cell_properties, 2))


def mesh_parts(mesh: Mesh) -> Parts:
    """The parts of :func:`tgsis.gmaps.from_mesh` (see it): darts, involutions, embedding."""
    from tgsis.mesh import Mesh as _Mesh

    if not isinstance(mesh, _Mesh) or type(mesh) is _Mesh:
        raise InvalidGeometryError(
            f"from_mesh takes a PointSet, LineSet, Surface or TetraMesh, got {type(mesh).__name__}",
            hint="convert each member of a collection",
        )
    return simplices_parts(mesh.vertices, mesh.cells, cell_properties=mesh.cell_properties, size=mesh.cell_size)
