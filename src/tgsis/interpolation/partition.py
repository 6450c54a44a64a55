"""Partition of source and target into patches, and the pairing of their patches.

Fence paths and the border split a mesh into **patches**: the triangles are
flood-filled across every edge that is not on a fence path (border edges join
nothing). Each patch must be a topological disk with at least 3 control
vertices, all on its border. Source and target must have as many patches, and
the patches pair up by their control vertices (position ``i`` of the source's
control sequence pairs with position ``i`` of the target's) in the same cyclic
order along the patch borders.

Every check reports all that is wrong at once, each problem naming the patch
(its index, a few of its triangles, its control vertices) or the path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tgsis.interpolation.constraints import fence_label, validate_fence_paths
from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.topology import MeshTopology, check_disk, few, mesh_topology, named
from tgsis.mesh import Surface

__all__ = ["Patch", "Partition", "PatchPair", "PartitionPairing", "partition_surface", "pair_patches", "partition_pair"]

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class Patch:
    """One patch of a partitioned mesh.

    Attributes
    ----------
    index : int
        Position in :attr:`Partition.patches` (patches are numbered in the
        order of their lowest triangle).
    triangles : (f,) int64
        Indices into the mesh's triangles, ascending.
    vertices : (v,) int64
        Mesh vertices of the patch, ascending.
    border : (b,) int64
        The border loop, oriented like the triangles, starting at the control
        vertex that comes first in the mesh's control sequence.
    corners : (k,) int64
        Positions in ``border`` of the control vertices (``corners[0] == 0``), ascending.
    control_vertices : (k,) int64
        ``border[corners]``: the control vertices in border order.
    control_indices : (k,) int64
        Position of each in the mesh's control sequence, i.e. the control
        vertex pair it belongs to.
    """

    index: int
    triangles: IntArray
    vertices: IntArray
    border: IntArray
    corners: IntArray
    control_vertices: IntArray
    control_indices: IntArray


@dataclass(frozen=True)
class Partition:
    """A mesh split into patches by its fence paths and border.

    Attributes
    ----------
    mesh_name : str
        ``"source"`` or ``"target"``.
    control_vertices : (c,) int64
        The mesh's control vertex sequence.
    fence_paths : tuple of (k_i,) int64
        The fence paths.
    triangle_patch : (m,) int64
        Patch of each triangle.
    patches : tuple of Patch
    """

    mesh_name: str
    control_vertices: IntArray
    fence_paths: tuple[IntArray, ...]
    triangle_patch: IntArray
    patches: tuple[Patch, ...]


@dataclass(frozen=True)
class PatchPair:
    """A source patch and the target patch it morphs into.

    Both patches' borders start at the same control vertex pair and list their
    control vertices in the same cyclic order: ``source.control_vertices[j]``
    pairs with ``target.control_vertices[j]``.

    Attributes
    ----------
    source, target : int
        Patch indices.
    control_indices : (k,) int64
        The control vertex pairs (positions in the control sequences), in
        border order.
    """

    source: int
    target: int
    control_indices: IntArray


@dataclass(frozen=True)
class PartitionPairing:
    """Both partitions and the pairing of their patches.

    Attributes
    ----------
    source, target : Partition
    pairs : tuple of PatchPair
        One per source patch, in source patch order.
    """

    source: Partition
    target: Partition
    pairs: tuple[PatchPair, ...]


def _patch_label(mesh_name: str, index: int, triangles: IntArray, controls: IntArray) -> str:
    return (
        f"{mesh_name} patch {index} (triangles {few(triangles, 4)}; "
        f"control vertices [{', '.join(str(v) for v in controls.tolist())}])"
    )


def partition_surface(
    mesh: Surface | MeshTopology,
    control_vertices: npt.ArrayLike,
    fence_paths: Sequence[npt.ArrayLike] = (),
    *,
    fence_names: Sequence[str | None] | None = None,
    mesh_name: str = "source",
) -> Partition:
    """Split a mesh into patches along its fence paths and check each patch.

    Parameters
    ----------
    mesh : Surface or MeshTopology
    control_vertices : (c,) array_like of int
        The mesh's control vertex sequence.
    fence_paths : sequence of (k_i,) array_like of int
        Fence paths (validated by
        :func:`~tgsis.interpolation.constraints.validate_fence_paths`).
    fence_names : sequence of str or None, optional
        Names of the fence paths, for messages.
    mesh_name : str
        ``"source"`` or ``"target"``, for messages.

    Returns
    -------
    Partition

    Raises
    ------
    InterpolationSetupError
        Bad control vertices or fence paths; a fence path that separates
        nothing (the same patch on both sides); a patch that is not a disk, has
        fewer than 3 control vertices, or has control vertices inside. All
        problems are listed, each naming its patch or path.
    """
    topo = mesh_topology(mesh)
    paths = validate_fence_paths(topo, fence_paths, control_vertices, names=fence_names, mesh_name=mesh_name)
    controls = np.asarray(control_vertices, dtype=np.int64).reshape(-1)
    fence_edges = [topo.find_edges(np.stack([p[:-1], p[1:]], axis=1)) for p in paths]
    blocked = np.zeros(len(topo.edges), dtype=bool)
    for e in fence_edges:
        blocked[e] = True
    labels, count = topo.triangle_components(blocked)
    problems: list[str] = []

    for i, e in enumerate(fence_edges):
        sides = topo.edge_triangles[e]
        inner = sides[:, 1] >= 0
        same = np.flatnonzero(inner & (labels[sides[:, 0]] == labels[np.where(inner, sides[:, 1], 0)]))
        if same.size:
            a, b = topo.edges[e[same[0]]].tolist()
            problems.append(
                f"{fence_label(mesh_name, i, fence_names)} separates nothing: both sides of its edge "
                f"({a}, {b}) are in {mesh_name} patch {labels[sides[same[0], 0]]}"
                + (f" ({same.size} of its edges are so)" if same.size > 1 else "")
                + "; a fence path must run from border to border or between other fence paths"
            )

    control_index = np.full(topo.n_vertices, -1, dtype=np.int64)
    control_index[controls] = np.arange(len(controls))
    order = np.argsort(labels, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(labels, minlength=count))])
    patches: list[Patch] = []
    for p in range(count):
        tris = np.sort(order[bounds[p] : bounds[p + 1]])
        used, local = np.unique(topo.triangles[tris], return_inverse=True)
        patch_controls = used[control_index[used] >= 0]
        patch_controls = patch_controls[np.argsort(control_index[patch_controls])]
        label = _patch_label(mesh_name, p, tris, patch_controls)
        local_topo = MeshTopology(local.reshape(-1, 3), len(used))
        disk = check_disk(local_topo, vertex_ids=used)
        if not disk.ok:
            problems.append(f"{label} is not a disk: {disk.summary()}")
            continue
        border = used[local_topo.border_loops[0]]
        on_border = control_index[border] >= 0
        if on_border.sum() < len(patch_controls):
            inside = np.setdiff1d(patch_controls, border)
            problems.append(f"{label}: {named('control vertex', inside)} inside the patch, not on its border")
        if len(patch_controls) < 3:
            problems.append(
                f"{label} has {len(patch_controls)} control vertices: a patch needs at least 3 "
                "(the corners of its polygon)"
            )
        if problems:
            continue
        start = int(np.flatnonzero(border == patch_controls[0])[0])
        border = np.roll(border, -start)
        corners = np.flatnonzero(control_index[border] >= 0).astype(np.int64)
        patches.append(
            Patch(
                p,
                tris.astype(np.int64),
                used.astype(np.int64),
                border.astype(np.int64),
                corners,
                border[corners],
                control_index[border[corners]],
            )
        )
    if problems:
        raise InterpolationSetupError.collect(f"{mesh_name} partition", problems)
    return Partition(mesh_name, controls, paths, labels, tuple(patches))


def _describe(patch: Patch, partition: Partition) -> str:
    return (
        f"{partition.mesh_name} patch {patch.index} (control vertex pairs "
        f"[{', '.join(str(v) for v in patch.control_indices.tolist())}], {partition.mesh_name} vertices "
        f"[{', '.join(str(v) for v in patch.control_vertices.tolist())}])"
    )


def pair_patches(source: Partition, target: Partition) -> tuple[PatchPair, ...]:
    """Pair the patches of source and target by their control vertex pairs.

    Parameters
    ----------
    source, target : Partition
        From :func:`partition_surface`; position ``i`` of the source's control
        sequence pairs with position ``i`` of the target's.

    Returns
    -------
    tuple of PatchPair
        One per source patch, in order.

    Raises
    ------
    InterpolationSetupError
        Control sequences of different lengths, different numbers of patches,
        a patch with no counterpart, the same control vertices in another
        cyclic order, two patches of one mesh with the same control vertices.
    """
    if len(source.control_vertices) != len(target.control_vertices):
        raise InterpolationSetupError(
            f"{source.mesh_name} has {len(source.control_vertices)} control vertices and {target.mesh_name} "
            f"{len(target.control_vertices)}: control vertices pair up by position in the two sequences"
        )
    problems: list[str] = []
    if len(source.patches) != len(target.patches):

        def listing(part: Partition) -> str:
            return "; ".join(
                f"{q.index}: [{', '.join(str(v) for v in q.control_indices.tolist())}]" for q in part.patches
            )

        problems.append(
            f"{source.mesh_name} has {len(source.patches)} patches and {target.mesh_name} "
            f"{len(target.patches)}: every patch needs a counterpart (control vertex pairs of each "
            f"{source.mesh_name} patch {listing(source)}; {target.mesh_name} patch {listing(target)})"
        )

    def keyed(part: Partition) -> dict[tuple[int, ...], Patch]:
        found: dict[tuple[int, ...], Patch] = {}
        for q in part.patches:
            key = tuple(q.control_indices.tolist())  # starts at its smallest pair: a canonical rotation
            if key in found:
                problems.append(
                    f"{_describe(found[key], part)} and {part.mesh_name} patch {q.index} have the "
                    "same control vertex pairs in the same order: cannot tell which patch pairs with "
                    "which; add a control vertex to one of them"
                )
            found.setdefault(key, q)
        return found

    target_keys = keyed(target)
    keyed(source)
    pairs: list[PatchPair] = []
    matched: set[int] = set()
    for q in source.patches:
        key = tuple(q.control_indices.tolist())
        if key in target_keys:
            t = target_keys[key]
            pairs.append(PatchPair(q.index, t.index, q.control_indices))
            matched.add(t.index)
            continue
        same_set = [t for t in target.patches if sorted(t.control_indices.tolist()) == sorted(key)]
        if same_set:
            t = same_set[0]
            reversed_order = tuple(np.roll(t.control_indices[::-1], 1).tolist()) == key
            problems.append(
                f"{_describe(q, source)} and {_describe(t, target)} have the same control vertex pairs "
                "in a different cyclic order along their borders"
                + (" (reversed: are the triangles of one mesh oriented the other way?)" if reversed_order else "")
            )
            matched.add(t.index)
        else:
            problems.append(
                f"{_describe(q, source)} has no {target.mesh_name} patch with the same control vertex pairs"
            )
    for t in target.patches:
        if t.index not in matched:
            problems.append(
                f"{_describe(t, target)} has no {source.mesh_name} patch with the same control vertex pairs"
            )
    if problems:
        raise InterpolationSetupError.collect("patch pairing", problems)
    return tuple(pairs)


def partition_pair(
    source: Surface | MeshTopology,
    target: Surface | MeshTopology,
    source_controls: npt.ArrayLike,
    target_controls: npt.ArrayLike,
    source_fences: Sequence[npt.ArrayLike] = (),
    target_fences: Sequence[npt.ArrayLike] = (),
    *,
    source_fence_names: Sequence[str | None] | None = None,
    target_fence_names: Sequence[str | None] | None = None,
) -> PartitionPairing:
    """Partition source and target and pair their patches, reporting every problem of both at once.

    Parameters
    ----------
    source, target : Surface or MeshTopology
    source_controls, target_controls : (c,) array_like of int
        Control vertex sequences; position ``i`` of one pairs with position ``i`` of the other.
    source_fences, target_fences : sequence of (k_i,) array_like of int
        Fence paths of each mesh.
    source_fence_names, target_fence_names : sequence of str or None, optional
        Names of the fence paths, for messages.

    Returns
    -------
    PartitionPairing

    Raises
    ------
    InterpolationSetupError
        See :func:`partition_surface` and :func:`pair_patches`.
    """
    problems: list[str] = []
    n_source, n_target = np.size(source_controls), np.size(target_controls)
    if n_source != n_target:
        problems.append(
            f"source has {n_source} control vertices and target {n_target}: control vertices pair "
            "up by position in the two sequences"
        )
    parts: list[Partition] = []
    for mesh, controls, fences, names, name in (
        (source, source_controls, source_fences, source_fence_names, "source"),
        (target, target_controls, target_fences, target_fence_names, "target"),
    ):
        try:
            parts.append(partition_surface(mesh, controls, fences, fence_names=names, mesh_name=name))
        except InterpolationSetupError as exc:
            problems.extend(exc.problems)
    if problems:
        raise InterpolationSetupError.collect("interpolation set-up", problems)
    return PartitionPairing(parts[0], parts[1], pair_patches(parts[0], parts[1]))
