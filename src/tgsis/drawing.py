"""What a mesh looks like to a viewer: the cells to draw, the values to colour by (numpy only; no database).

A stored geometry of any model, a G-map of any dimension up to 3, is drawn
as one of three kinds: ``triangles`` (3 indices per cell), ``lines`` (2) or
``points`` (none), with the numeric vertex values to colour by and, per
drawn cell, the stored cell it comes from. The database layer builds these
from stored rows (so the browser view composes no SQL), the browser view
(:mod:`tgsis.view.meshes`) sends them as binary arrays, and pictures may
draw them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from tgsis._polygons import fan_triangles
from tgsis.errors import InvalidInputError
from tgsis.gmaps import GMap
from tgsis.mesh import Geometry, GeometryCollection, LineSet, Mesh, Surface, TetraMesh

__all__ = ["Drawable", "StoredSurface", "drawable", "gmap_drawable", "tetra_boundary", "vertex_flags"]

Kind = Literal["triangles", "lines", "points"]

#: the faces of a tetrahedron (a, b, c, d), each as three of its corners
_TETRA_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


class Drawable:
    """A mesh as the browser draws it.

    Attributes
    ----------
    kind : {"triangles", "lines", "points"}
    vertices : (n, 3) float64
    indices : (m, k) int64
        k = 3 (triangles), 2 (lines) or 0 (points).
    vertex_values : dict of str to (n,) float64
        The numeric scalar vertex properties (a vector's first component is left out).
    cell_rows : (m,) int64
        For each drawn cell, the index of the stored cell it comes from (a
        tetrahedron's boundary faces point at their tetrahedron).
    """

    def __init__(
        self,
        kind: Kind,
        vertices: npt.NDArray[np.float64],
        indices: npt.NDArray[np.int64],
        vertex_values: Mapping[str, npt.NDArray[np.float64]],
        cell_rows: npt.NDArray[np.int64],
    ) -> None:
        self.kind = kind
        self.vertices = vertices
        self.indices = indices
        self.vertex_values = dict(vertex_values)
        self.cell_rows = cell_rows


@dataclass(frozen=True)
class StoredSurface:
    """A surface as stored, in ascending id order: what the view compares between two versions.

    A data model's ``surface`` hook (:class:`tgsis.datamodels.Storage`) gives it.

    Attributes
    ----------
    drawable : Drawable
        Triangles; ``vertex_values`` holds the property asked for, if any.
    vertex_ids, triangle_ids : (n,) and (m,) int64
        Stored ids of the vertices and triangles (for model 1 ``vrtxid``, ``trglid``), ascending.
    """

    drawable: Drawable
    vertex_ids: npt.NDArray[np.int64]
    triangle_ids: npt.NDArray[np.int64]


def tetra_boundary(tetrahedra: npt.ArrayLike) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """The faces of a tetrahedral mesh that belong to one tetrahedron only (its boundary).

    Parameters
    ----------
    tetrahedra : (m, 4) array_like of int

    Returns
    -------
    faces : (f, 3) int64
        Vertex indices, oriented outwards for positively oriented tetrahedra.
    owner : (f,) int64
        The tetrahedron of each face.
    """
    tets = np.asarray(tetrahedra, dtype=np.int64).reshape(-1, 4)
    faces = tets[:, _TETRA_FACES].reshape(-1, 3)
    owner = np.repeat(np.arange(len(tets), dtype=np.int64), 4)
    if len(faces) == 0:
        return faces, owner
    _, inverse, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
    once = counts[inverse.ravel()] == 1
    return faces[once], owner[once]


def _scalars(mesh: Mesh) -> dict[str, npt.NDArray[np.float64]]:
    values = {}
    for name, array in mesh.vertex_properties.items():
        a = np.asarray(array)
        if a.ndim == 1 and np.issubdtype(a.dtype, np.number):
            values[name] = a.astype(np.float64)
    return values


def _one(mesh: Mesh) -> Drawable:
    if isinstance(mesh, Surface):
        return Drawable("triangles", mesh.vertices, mesh.cells, _scalars(mesh), np.arange(len(mesh.cells)))
    if isinstance(mesh, TetraMesh):
        faces, owner = tetra_boundary(mesh.cells)
        return Drawable("triangles", mesh.vertices, faces, _scalars(mesh), owner)
    if isinstance(mesh, LineSet):
        return Drawable("lines", mesh.vertices, mesh.cells, _scalars(mesh), np.arange(len(mesh.cells)))
    return Drawable(
        "points", mesh.vertices, np.empty((0, 0), dtype=np.int64), _scalars(mesh), np.empty(0, dtype=np.int64)
    )


def drawable(geometry: Geometry) -> Drawable:
    """What to draw of a mesh or a collection.

    A collection's members of the highest kind present (triangles, then
    lines, then points) are drawn as one mesh; the vertex properties kept are
    those every such member has.
    """
    if not isinstance(geometry, GeometryCollection):
        return _one(geometry)
    parts = [_one(m) for m in geometry]
    for kind in ("triangles", "lines", "points"):
        chosen = [p for p in parts if p.kind == kind]
        if chosen:
            break
    offsets = np.cumsum([0] + [len(p.vertices) for p in chosen])
    k = chosen[0].indices.shape[1] if chosen[0].indices.ndim == 2 else 0
    names = set.intersection(*(set(p.vertex_values) for p in chosen))
    cells = np.concatenate([p.cell_rows for p in chosen]) if chosen else np.empty(0, dtype=np.int64)
    return Drawable(
        chosen[0].kind,
        np.concatenate([p.vertices for p in chosen]).reshape(-1, 3),
        np.concatenate([p.indices + o for p, o in zip(chosen, offsets)]).reshape(-1, k),
        {n: np.concatenate([p.vertex_values[n] for p in chosen]) for n in sorted(names)},
        cells,
    )


def gmap_drawable(g: GMap, axes: Sequence[str] = ("x", "y", "z")) -> Drawable:
    """What to draw of a G-map: its faces (n = 2), the faces of its border (n = 3), edges (n = 1) or points.

    Positions are the first three coordinates of the embedding (R^m, m >= 3
    padded with zeros below); the coordinates beyond (a model-5 map's
    knowledge or time axes, named by ``axes``) become vertex values to colour
    by. ``cell_rows`` are the faces (2-cells of the map, or of its border).

    Raises
    ------
    InvalidInputError
        A map of dimension n > 3 (its faces are not a surface in space).
    """
    n, m = g.dimension, g.embedding_dimension
    if n > 3:
        raise InvalidInputError(f"a {n}-G-map is not drawn: the browser view draws G-maps of dimension 0 to 3")
    vertices = np.zeros((g.n_points, 3))
    vertices[:, : min(m, 3)] = g.points[:, :3]
    values = {(axes[i] if i < len(axes) else f"axis {i + 1}"): g.points[:, i].astype(np.float64) for i in range(3, m)}
    surface = g.border() if n == 3 else g
    if n >= 2:
        triangles, face = (
            fan_triangles(*surface.polygons())
            if surface.n_darts
            else (np.empty((0, 3), dtype=np.int64), np.empty(0, dtype=np.int64))
        )
        return Drawable("triangles", vertices, triangles, values, face)
    if n == 1:
        first = g.cell_darts(1)
        edges = np.stack([g.vertex[first], g.vertex[g.alpha[0, first]]], axis=1)
        return Drawable("lines", vertices, edges, values, np.arange(len(edges), dtype=np.int64))
    return Drawable("points", vertices, np.empty((0, 0), dtype=np.int64), values, np.empty(0, dtype=np.int64))


def vertex_flags(n_vertices: int, marked: Sequence[tuple[int, npt.ArrayLike]]) -> npt.NDArray[np.float32]:
    """A value per vertex: the sum of the flags of the groups it belongs to (0 for none).

    Parameters
    ----------
    n_vertices : int
    marked : sequence of (flag, (k,) int array_like)
        Vertex indices carrying ``flag`` (1, 2, 4, ...).
    """
    flags = np.zeros(n_vertices, dtype=np.int64)
    for flag, indices in marked:
        idx = np.unique(np.asarray(indices, dtype=np.int64))
        flags[idx] |= flag
    return flags.astype(np.float32)
