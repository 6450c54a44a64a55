"""Checks of the user's constraints on one mesh: control vertices and fence paths.

A **fence path** is an edge path between two control vertices with no other
control vertex inside; the fence paths of one mesh meet only at their end
vertices (they share no inner vertex and no edge). Fence paths and the border
split the mesh into patches (:mod:`tgsis.interpolation.partition`).
:func:`~tgsis.interpolation.topology.shortest_edge_path` proposes one, given
the other control vertices to avoid.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.topology import MeshTopology, mesh_topology, named, path_problems
from tgsis.mesh import Surface

__all__ = ["fence_label", "validate_control_vertices", "validate_fence_paths"]

IntArray = npt.NDArray[np.int64]


def fence_label(mesh_name: str, index: int, names: Sequence[str | None] | None = None) -> str:
    """How messages name a fence path: ``"source fence path 2 ('east')"``."""
    name = names[index] if names is not None and index < len(names) else None
    return f"{mesh_name} fence path {index}" + (f" ({name!r})" if name else "")


def validate_control_vertices(
    mesh: Surface | MeshTopology, control_vertices: npt.ArrayLike, *, mesh_name: str = "source"
) -> IntArray:
    """Check a control vertex sequence: vertex indices of the mesh, each on a triangle, none twice.

    Parameters
    ----------
    mesh : Surface or MeshTopology
    control_vertices : (k,) array_like of int
        Control vertices; position ``i`` pairs with position ``i`` of the other
        mesh's sequence.
    mesh_name : str
        ``"source"`` or ``"target"``, for messages.

    Returns
    -------
    (k,) int64

    Raises
    ------
    InterpolationSetupError
        Naming the offending vertices and their positions in the sequence.
    """
    topo = mesh_topology(mesh)
    raw = np.asarray(control_vertices)
    if raw.ndim != 1 or (raw.size and raw.dtype.kind not in "iu"):
        raise InterpolationSetupError(
            f"{mesh_name} control vertices are not a sequence of vertex indices (shape {raw.shape}, type {raw.dtype})"
        )
    verts = raw.astype(np.int64)
    n = topo.n_vertices
    problems: list[str] = []
    outside = np.flatnonzero((verts < 0) | (verts >= n))
    if outside.size:
        problems.append(
            f"{mesh_name} {named('control vertex', verts[outside])} ({named('position', outside)}): "
            f"not in the mesh, which has {n} vertices"
        )
    else:
        order = np.argsort(verts, kind="stable")
        for r in np.flatnonzero(verts[order][1:] == verts[order][:-1])[:3]:
            problems.append(
                f"{mesh_name} control vertex {verts[order[r]]} is given twice (positions {order[r]} and {order[r + 1]})"
            )
        loose = np.flatnonzero(~topo.used_vertices[verts])
        if loose.size:
            problems.append(
                f"{mesh_name} {named('control vertex', verts[loose])} ({named('position', loose)}): on no triangle"
            )
    if problems:
        raise InterpolationSetupError.collect(f"{mesh_name} control vertices", problems)
    return verts


def validate_fence_paths(
    mesh: Surface | MeshTopology,
    fence_paths: Sequence[npt.ArrayLike],
    control_vertices: npt.ArrayLike,
    *,
    names: Sequence[str | None] | None = None,
    mesh_name: str = "source",
) -> tuple[IntArray, ...]:
    """Check the fence paths of one mesh.

    Each must be an edge path (consecutive vertices share an edge, no vertex
    twice) from a control vertex to another with no control vertex inside; two
    fence paths may share end vertices only.

    Parameters
    ----------
    mesh : Surface or MeshTopology
    fence_paths : sequence of (k_i,) array_like of int
        Vertex sequences.
    control_vertices : (c,) array_like of int
        The mesh's control vertices.
    names : sequence of str or None, optional
        Names of the paths, for messages.
    mesh_name : str
        ``"source"`` or ``"target"``, for messages.

    Returns
    -------
    tuple of (k_i,) int64
        The paths.

    Raises
    ------
    InterpolationSetupError
        Listing every problem, each naming the path (index and name) and the
        offending vertex or edge.
    """
    topo = mesh_topology(mesh)
    controls = validate_control_vertices(topo, control_vertices, mesh_name=mesh_name)
    is_control = np.zeros(topo.n_vertices, dtype=bool)
    is_control[controls] = True
    problems: list[str] = []
    paths: list[IntArray] = []
    edges: list[IntArray] = []
    for i, path in enumerate(fence_paths):
        label = fence_label(mesh_name, i, names)
        verts, edge_ids, found = path_problems(topo, path, label)
        if not found:
            for which, v in (("starts", verts[0]), ("ends", verts[-1])):
                if not is_control[v]:
                    found.append(f"{label} {which} at vertex {v}, which is not a {mesh_name} control vertex")
            inside = np.flatnonzero(is_control[verts[1:-1]]) + 1
            if inside.size:
                found.append(
                    f"{label} passes through {named('control vertex', verts[inside])} "
                    f"({named('position', inside)}): a fence path joins two control vertices with none "
                    "in between; "
                    "split it there"
                )
        problems.extend(found)
        paths.append(verts)
        edges.append(edge_ids if not found else np.empty(0, dtype=np.int64))
    good = [i for i, e in enumerate(edges) if len(e)]
    if len(good) > 1:
        problems.extend(_crossings(topo, [paths[i] for i in good], [edges[i] for i in good], good, names, mesh_name))
    if problems:
        raise InterpolationSetupError.collect(f"{mesh_name} fence paths", problems)
    return tuple(paths)


def _crossings(
    topo: MeshTopology,
    paths: list[IntArray],
    edges: list[IntArray],
    index: list[int],
    names: Sequence[str | None] | None,
    mesh_name: str,
) -> list[str]:
    """Pairs of fence paths that share an inner vertex or an edge."""
    problems: list[str] = []
    owner = np.concatenate([np.full(len(p), i, dtype=np.int64) for i, p in enumerate(paths)])
    vertex = np.concatenate(paths)
    inner = np.concatenate([np.r_[False, np.ones(len(p) - 2, dtype=bool), False] for p in paths])
    order = np.lexsort((owner, vertex))
    owner, vertex, inner = owner[order], vertex[order], inner[order]
    starts = np.flatnonzero(np.r_[True, vertex[1:] != vertex[:-1]])
    size = np.diff(np.r_[starts, len(vertex)])
    reported: set[tuple[int, int]] = set()
    for s, k in zip(starts[size > 1].tolist(), size[size > 1].tolist()):
        where = slice(s, s + k)
        if not inner[where].any():
            continue  # paths meeting at a common end vertex
        holders = owner[where]
        for a in range(k):
            for b in range(a + 1, k):
                if not (inner[s + a] or inner[s + b]):
                    continue
                pair = (int(holders[a]), int(holders[b]))
                if pair in reported:
                    continue
                reported.add(pair)
                first, second = (fence_label(mesh_name, index[j], names) for j in pair)
                inside = " and ".join(lbl for lbl, flag in ((first, inner[s + a]), (second, inner[s + b])) if flag)
                problems.append(
                    f"{first} and {second} meet at vertex {vertex[s]}, which is inside {inside}: "
                    "fence paths may meet at their end vertices only"
                )
    edge_owner = np.concatenate([np.full(len(e), i, dtype=np.int64) for i, e in enumerate(edges)])
    edge = np.concatenate(edges)
    order = np.lexsort((edge_owner, edge))
    edge, edge_owner = edge[order], edge_owner[order]
    for r in np.flatnonzero(edge[1:] == edge[:-1]).tolist():
        pair = (int(edge_owner[r]), int(edge_owner[r + 1]))
        if pair in reported:
            continue
        reported.add(pair)
        a, b = topo.edges[edge[r]].tolist()
        first, second = (fence_label(mesh_name, index[j], names) for j in pair)
        problems.append(
            f"{first} and {second} share the edge ({a}, {b}): fence paths may meet at their end vertices only"
        )
    return problems
