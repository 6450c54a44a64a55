"""Three-way merge of one mesh: the edits of two sides, by row id, merged per region (docs/merge.md).

The three states of one object — ``base`` (as the version was based on it),
``parent`` and ``child`` — are given as the database holds them: id-keyed rows
of vertices (id, x, y, z, property values) and cells (id, vertex ids,
property values), for points, segments, triangles and tetrahedra alike
(:class:`MeshState`). An *edit* of a side is a row whose state there differs
from the base's. Edits are grouped into *regions*: a side's changed vertices
and cells, grown by a one-ring margin (the cells around a vertex it moved,
added or removed; the vertices of a cell it added, removed or reconnected),
connected through shared cells; regions of the two sides that share a vertex
or cell are one region. A region only one side touched, or where both sides
give the same rows, merges by itself; the others are *conflicts*, solved per
region (``parent``, ``child``, ``base`` or a manual state) by
:func:`apply_solutions`, which says what each solution discards and refuses a
result that is not a valid mesh (:class:`~tgsis.errors.InvalidMergeError`).

The child's new ids are renumbered where the parent gave the same id to
something else (:attr:`MeshMerge.child_vertex_renumbering`), so that the
parent's ids — the ones a merge into the parent keeps — never change.

Pure numpy and scipy (regions: ``scipy.sparse.csgraph.connected_components``
over the changed elements only); nothing here reads a database. The cost is
a few passes over the rows plus work proportional to the change.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, TypeAlias

import numpy as np
import numpy.typing as npt

from tgsis.errors import (
    InvalidGeometryError,
    InvalidInputError,
    InvalidMergeError,
    InvalidPropertyError,
    UnsolvedConflictsError,
)
from tgsis.mesh import Mesh, mesh_class

__all__ = [
    "MeshState",
    "MergeRegion",
    "MeshMerge",
    "RegionDiscard",
    "ResolvedMerge",
    "Solution",
    "three_way_merge",
    "apply_solutions",
]

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Positions: TypeAlias = "IntArray | slice"

#: What a conflicting region takes: one side's rows, the base's, or a manual state (docs/merge.md).
Solution: TypeAlias = "Literal['parent', 'child', 'base'] | MeshState"

_CELL_WORDS = {1: "point", 2: "segment", 3: "triangle", 4: "tetrahedron"}
_SHOWN = 10  # ids a message names before "..."


def ids_text(ids: npt.ArrayLike) -> str:
    """Ids for a message: the first few, and how many in all when there are more."""
    values = np.asarray(ids).ravel().tolist()
    shown = ", ".join(str(v) for v in values[:_SHOWN])
    return shown + (f", ... ({len(values)} in all)" if len(values) > _SHOWN else "")


def _strictly_increasing(ids: IntArray) -> bool:
    return len(ids) < 2 or bool(np.all(ids[1:] > ids[:-1]))


_TABLE_FROM = 1 << 14  # ids looked up through a table of positions from this many on both sides


def _positions(sorted_ids: IntArray, query: IntArray) -> IntArray:
    """Per query id, its position in ``sorted_ids`` (strictly increasing), or -1.

    Many ids in many ids over a range not much larger than their number (the
    usual: ids 0..n-1 with a few gaps) go through a table of positions, one
    gather; else a binary search.
    """
    if len(sorted_ids) == 0:
        return np.full(np.shape(query), -1, dtype=np.int64)
    if np.size(query) >= _TABLE_FROM and len(sorted_ids) >= _TABLE_FROM:
        lo, hi = int(sorted_ids[0]), int(sorted_ids[-1])
        if hi - lo <= 4 * len(sorted_ids):
            table = np.full(hi - lo + 3, -1, dtype=np.int64)  # a -1 pad on each side: clipped lookups hit it
            table[np.subtract(sorted_ids, np.int64(lo), dtype=np.int64) + 1] = np.arange(
                len(sorted_ids), dtype=np.int64
            )
            return np.take(table, _offsets(query, lo), mode="clip")
    pos = np.searchsorted(sorted_ids, query)
    np.minimum(pos, len(sorted_ids) - 1, out=pos)
    return np.where(sorted_ids[pos] == query, pos, -1).astype(np.int64)


def _offsets(query: IntArray, lo: int) -> npt.NDArray[np.int64]:
    """``query - lo + 1`` in int64, for a lookup table over ids from ``lo`` with a pad at each end (clipped).

    Computed modulo 2**64 (numpy's int64 wraps): an id in the table's range
    lands on its entry, any other outside it, where the clip meets a pad.
    ``lo - 1`` itself is not an int64 when ``lo`` is -2**63 (a vertex id a
    psql user may write): an OverflowError before.
    """
    return np.subtract(query, np.int64(lo), dtype=np.int64) + np.int64(1)


def _contains(sorted_ids: IntArray, query: IntArray) -> BoolArray:
    return _positions(sorted_ids, query) >= 0


def _flags(keys: IntArray, flags: npt.NDArray[np.uint8], query: IntArray) -> npt.NDArray[np.uint8]:
    """Per element of ``query`` (any shape), the flag of the equal key (sorted, unique), or 0.

    A table over the keys' range when it is small enough (one gather), else a
    binary search: this runs over every cell of a large mesh.
    """
    if len(keys) == 0:
        return np.zeros(np.shape(query), dtype=np.uint8)
    lo, hi = int(keys[0]), int(keys[-1])
    if hi - lo < (1 << 27):
        table = np.zeros(hi - lo + 3, dtype=np.uint8)  # one zero pad on each side: clipped lookups hit it
        table[np.subtract(keys, np.int64(lo), dtype=np.int64) + 1] = flags
        return np.take(table, _offsets(query, lo), mode="clip")
    pos = _positions(keys, query)
    return np.where(pos >= 0, flags[np.maximum(pos, 0)], 0).astype(np.uint8)


def _cell_hits(keys: IntArray, cells: IntArray) -> BoolArray:
    """Per cell, whether any of its vertex ids is one of ``keys`` (sorted, unique)."""
    ones = np.ones(len(keys), dtype=np.uint8)
    hit = np.zeros(len(cells), dtype=np.uint8)
    for j in range(cells.shape[1]):
        hit |= _flags(keys, ones, cells[:, j])
    return hit.astype(bool)


def _canonical_cells(cells: IntArray) -> IntArray:
    """(m, k + 1): each cell's vertex ids ascending, then the parity of its order (same oriented cell, same row)."""
    k = cells.shape[1]
    parity = np.zeros(len(cells), dtype=np.int64)
    for i in range(k):
        for j in range(i + 1, k):
            parity ^= (cells[:, i] > cells[:, j]).astype(np.int64)
    return np.concatenate([np.sort(cells, axis=1), parity[:, None]], axis=1)


def _same_rows(a: npt.NDArray[Any], b: npt.NDArray[Any]) -> BoolArray:
    """Per row of two (n, c) arrays, whether all c values are equal (column by column: faster than all(axis=1))."""
    same = a[:, 0] == b[:, 0]
    for j in range(1, a.shape[1]):
        same &= a[:, j] == b[:, j]
    return np.asarray(same, dtype=bool)


def _values_equal(a: npt.NDArray[Any], b: npt.NDArray[Any]) -> BoolArray:
    """Per row, whether two property arrays hold the same values (NaN equals NaN, -0.0 equals 0.0)."""
    same = a == b
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        same |= np.isnan(a) & np.isnan(b)
    if same.ndim > 1:
        same = same.reshape(len(same), int(np.prod(same.shape[1:]))).all(axis=1)  # -1 fails on 0 rows
    return np.asarray(same, dtype=bool)


def _value_bits(values: npt.NDArray[Any]) -> npt.NDArray[np.uint64]:
    """(n, c) uint64 words of property values, equal words for equal values (one NaN, no -0.0)."""
    column = values.reshape(len(values), int(np.prod(values.shape[1:], dtype=np.int64)))
    if column.dtype.kind == "f" and column.dtype.itemsize > 8:
        # long double (64-bit integers with NaN for missing rows): two doubles whose sum is the value, exactly
        high = np.asarray(column, dtype=np.float64) + 0.0
        low = np.asarray(column - high.astype(column.dtype), dtype=np.float64) + 0.0
        both = np.concatenate([high, low], axis=1)
        both[np.isnan(both)] = np.nan
        return both.view(np.uint64)
    if column.dtype.kind == "f":
        floats = np.asarray(column, dtype=np.float64) + 0.0
        floats[np.isnan(floats)] = np.nan
        return floats.view(np.uint64)
    return np.asarray(column, dtype=np.int64).view(np.uint64)


@dataclass(frozen=True, eq=False)
class MeshState:
    """One object's mesh as id-keyed rows: what the database holds of it at one revision.

    Rows are kept ordered by id (sorted on construction when they are not).

    Attributes
    ----------
    cell_size : int
        k: 1 (points), 2 (segments), 3 (triangles) or 4 (tetrahedra).
    vertex_ids : (n,) int64
        Vertex row ids (``tgsis.vrtx.vrtxid``), unique.
    vertices : (n, 3) float64
        Their coordinates.
    cell_ids : (m,) int64
        Cell row ids (``pointid``, ``segid``, ``trglid``, ``tetraid``), unique.
    cells : (m, k) int64
        Each cell's vertex *ids* (not positions), in the row's order.
    vertex_properties, cell_properties : mapping of str to (n,) / (m,) or (n, c) / (m, c) arrays
        Numeric values per row (a NULL of the database as NaN).
    name : str
        Names the object in messages (``"faults 42"``).

    Raises
    ------
    InvalidGeometryError
        Wrong shapes, non-finite coordinates, repeated ids, a cell on a vertex
        id the state does not have or on one vertex twice.
    InvalidPropertyError
        A property with the wrong number of values or not numeric.
    """

    cell_size: int
    vertex_ids: IntArray
    vertices: FloatArray
    cell_ids: IntArray
    cells: IntArray
    vertex_properties: Mapping[str, npt.NDArray[Any]] = field(default_factory=dict)
    cell_properties: Mapping[str, npt.NDArray[Any]] = field(default_factory=dict)
    name: str = "mesh"

    def __post_init__(self) -> None:
        k = self.cell_size
        if k not in _CELL_WORDS:
            raise InvalidGeometryError(f"{self.name}: cells of {k} vertices: a mesh has cells of 1, 2, 3 or 4")
        vids = np.asarray(self.vertex_ids, dtype=np.int64).ravel()
        xyz = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 3) if np.size(self.vertices) else np.empty((0, 3))
        cids = np.asarray(self.cell_ids, dtype=np.int64).ravel()
        cells = np.asarray(self.cells, dtype=np.int64)
        cells = cells.reshape(-1, k) if cells.size else np.empty((0, k), dtype=np.int64)
        if len(vids) != len(xyz) or len(cids) != len(cells):
            raise InvalidGeometryError(
                f"{self.name}: {len(vids)} vertex ids for {len(xyz)} vertices, {len(cids)} cell ids for {len(cells)} cells"
            )
        if not np.all(np.isfinite(xyz)):
            bad = vids[~np.isfinite(xyz).all(axis=1)]
            raise InvalidGeometryError(f"{self.name}: vertices {ids_text(bad)} have non-finite coordinates")
        vprops = self._properties(self.vertex_properties, len(vids), "vertex")
        cprops = self._properties(self.cell_properties, len(cids), _CELL_WORDS[k])
        if not _strictly_increasing(vids):
            order = np.argsort(vids, kind="stable")
            vids, xyz = vids[order], xyz[order]
            vprops = {n: v[order] for n, v in vprops.items()}
        if not _strictly_increasing(cids):
            order = np.argsort(cids, kind="stable")
            cids, cells = cids[order], cells[order]
            cprops = {n: v[order] for n, v in cprops.items()}
        for what, ids in (("vertex", vids), (_CELL_WORDS[k], cids)):
            if len(ids) > 1 and not _strictly_increasing(ids):
                repeated = np.unique(ids[1:][ids[1:] == ids[:-1]])
                raise InvalidGeometryError(f"{self.name}: {what} ids {ids_text(repeated)} are given twice")
        if len(cells):
            dense = len(vids) > 0 and vids[0] == 0 and vids[-1] == len(vids) - 1
            missing = (cells < 0) | (cells >= len(vids)) if dense else ~_contains(vids, cells)
            if missing.any():
                rows = np.flatnonzero(missing.any(axis=1))
                raise InvalidGeometryError(
                    f"{self.name}: {_CELL_WORDS[k]}s {ids_text(cids[rows])} use vertex ids "
                    f"{ids_text(np.unique(cells[missing]))} that the mesh does not have"
                )
            repeated = np.zeros(len(cells), dtype=bool)
            for i in range(k):
                for j in range(i + 1, k):
                    repeated |= cells[:, i] == cells[:, j]
            if repeated.any():
                raise InvalidGeometryError(
                    f"{self.name}: {_CELL_WORDS[k]}s {ids_text(cids[repeated])} use a vertex twice"
                )
        for name, value in (("vertex_ids", vids), ("vertices", xyz), ("cell_ids", cids), ("cells", cells)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "vertex_properties", vprops)
        object.__setattr__(self, "cell_properties", cprops)

    def _properties(self, props: Mapping[str, Any], count: int, what: str) -> dict[str, npt.NDArray[Any]]:
        result: dict[str, npt.NDArray[Any]] = {}
        for name, values in props.items():
            array = np.asarray(values)
            if array.dtype.kind not in "biuf" or array.ndim not in (1, 2) or len(array) != count:
                raise InvalidPropertyError(
                    f"{self.name}: {what} property {name!r} has {len(array) if array.ndim else 0} values of "
                    f"type {array.dtype} and shape {array.shape}: one number (or vector) per {what} is needed, "
                    f"{count} in all"
                )
            result[name] = array
        return result

    @classmethod
    def from_mesh(
        cls,
        mesh: Mesh,
        vertex_ids: npt.ArrayLike | None = None,
        cell_ids: npt.ArrayLike | None = None,
        name: str | None = None,
    ) -> MeshState:
        """The state of a :class:`~tgsis.mesh.Mesh` with the given row ids (default: 0..n-1, 0..m-1, as uploaded).

        Parameters
        ----------
        mesh : Mesh
        vertex_ids : (n,) array_like of int, optional
        cell_ids : (m,) array_like of int, optional
        name : str, optional
            Default: the mesh's name, or ``"mesh"``.
        """
        vids = np.arange(mesh.n_vertices) if vertex_ids is None else np.asarray(vertex_ids, dtype=np.int64)
        cids = np.arange(mesh.n_cells) if cell_ids is None else np.asarray(cell_ids, dtype=np.int64)
        if len(vids) != mesh.n_vertices:
            raise InvalidGeometryError(f"{len(vids)} vertex ids for {mesh.n_vertices} vertices")
        return cls(
            mesh.cell_size,
            vids,
            mesh.vertices,
            cids,
            vids[mesh.cells],
            dict(mesh.vertex_properties),
            dict(mesh.cell_properties),
            name or mesh.name or "mesh",
        )

    def to_mesh(self) -> Mesh:
        """The mesh, vertices and cells in id order (cells as positions into the vertices)."""
        return mesh_class(_GEOTYPES[self.cell_size])(
            self.vertices,
            _positions(self.vertex_ids, self.cells),
            vertex_properties=self.vertex_properties,
            cell_properties=self.cell_properties,
            name=self.name,
        )

    @property
    def n_vertices(self) -> int:
        """Number of vertex rows n."""
        return len(self.vertex_ids)

    @property
    def n_cells(self) -> int:
        """Number of cell rows m."""
        return len(self.cell_ids)

    def _vertex_rows_equal(self, other: MeshState, mine: Positions, theirs: Positions) -> tuple[BoolArray, BoolArray]:
        """(equal rows, equal coordinates) of vertex rows at positions ``mine`` here and ``theirs`` there."""
        same_place = _same_rows(self.vertices[mine], other.vertices[theirs])
        same = same_place.copy()
        for name, values in self.vertex_properties.items():
            same &= _values_equal(values[mine], other.vertex_properties[name][theirs])
        return same, same_place

    def _cell_rows_equal(self, other: MeshState, mine: Positions, theirs: Positions) -> tuple[BoolArray, BoolArray]:
        """(equal rows, equal as oriented cells) of cell rows at these positions (a rotated row is the same cell)."""
        a, b = self.cells[mine], other.cells[theirs]
        same_cell = _same_rows(a, b)
        differ = np.flatnonzero(~same_cell)
        if len(differ):
            same_cell[differ] = np.all(_canonical_cells(a[differ]) == _canonical_cells(b[differ]), axis=1)
        same = same_cell.copy()
        for name, values in self.cell_properties.items():
            same &= _values_equal(values[mine], other.cell_properties[name][theirs])
        return same, same_cell


_GEOTYPES = {1: "MULTIPOINT", 2: "MULTILINESTRING", 3: "SURFACE", 4: "MULTITETRA"}


# ---------------------------------------------------------------- one side's edit


@dataclass(frozen=True)
class _Edit:
    """What one side changed against the base, by id (all arrays sorted)."""

    changed_vertices: IntArray  # moved, added, removed, or a property value changed
    shape_vertices: IntArray  # moved, added, removed: these grow the margin
    moved_vertices: IntArray
    changed_cells: IntArray  # added, removed, other vertices or orientation, or a property value changed
    topology_cells: IntArray  # added, removed, other vertices or orientation: their vertices join the margin


def _aligned(base_ids: IntArray, side_ids: IntArray) -> tuple[Positions, Positions, IntArray, IntArray]:
    """(base positions, side positions) of the common ids, the side's added ids, the base's removed ids.

    The same ids on both sides (the common case: nothing added or removed) give slices, which copy nothing.
    """
    if len(base_ids) == len(side_ids) and np.array_equal(base_ids, side_ids):
        return slice(None), slice(None), base_ids[:0], base_ids[:0]
    pos = _positions(base_ids, side_ids)
    found = pos >= 0
    hit = np.zeros(len(base_ids), dtype=bool)
    hit[pos[found]] = True
    return pos[found], np.flatnonzero(found).astype(np.int64), side_ids[~found], base_ids[~hit]


def _edit(base: MeshState, side: MeshState) -> _Edit:
    pb, ps, added, removed = _aligned(base.vertex_ids, side.vertex_ids)
    unchanged, in_place = base._vertex_rows_equal(side, pb, ps)
    common = base.vertex_ids[pb]
    moved = common[~in_place]
    shape = np.union1d(np.union1d(moved, added), removed)
    changed = np.union1d(shape, common[~unchanged])

    cb, cs, cadded, cremoved = _aligned(base.cell_ids, side.cell_ids)
    same, same_cell = base._cell_rows_equal(side, cb, cs)
    common = base.cell_ids[cb]
    topology = np.union1d(np.union1d(cadded, cremoved), common[~same_cell])
    changed_cells = np.union1d(topology, common[~same])
    return _Edit(changed, shape, moved, changed_cells, topology)


# ---------------------------------------------------------------- the child's new ids


#: the largest id a row can have (ids are bigint in the database)
_LARGEST_ID = 2**63 - 1


def _row_keys(parts: list[npt.NDArray[np.uint64]]) -> list[bytes]:
    rows = np.ascontiguousarray(np.concatenate(parts, axis=1))
    return [r.tobytes() for r in rows]


def _renumber(
    new_ids: IntArray,
    new_keys: list[bytes],
    other_ids: IntArray,
    other_keys: list[bytes],
    taken: IntArray,
    next_id: int,
    what: str,
    name: str,
) -> tuple[IntArray, int]:
    """Merged ids of one side's new rows: the other side's new row with the same content, else the same id
    when the other side does not use it, else a fresh id from ``next_id``.

    Raises
    ------
    InvalidMergeError
        A fresh id would pass the largest int64 (``what``: vertex or cell; ``name``: the object).
    """
    waiting: dict[bytes, list[int]] = {}
    for i, key in zip(other_ids.tolist()[::-1], other_keys[::-1]):
        waiting.setdefault(key, []).append(i)  # pop() hands out the lowest id first
    result = new_ids.copy()
    matched = np.zeros(len(new_ids), dtype=bool)
    for n, key in enumerate(new_keys):
        queue = waiting.get(key)
        if queue:
            result[n] = queue.pop()
            matched[n] = True
    unmatched = np.flatnonzero(~matched)
    clash = unmatched[_contains(taken, new_ids[unmatched])]  # the other side's ids, matched ones among them
    if len(clash) and next_id + len(clash) - 1 > _LARGEST_ID:
        raise InvalidMergeError(
            f"{name}: the version's new {what} ids {ids_text(new_ids[clash])} are the parent's too and must be "
            f"renumbered above {next_id - 1}, which leaves no id in a bigint",
            hint="solve the object as a whole (resolve_conflict with parent, child or manual), or give the new rows "
            "smaller ids",
        )
    result[clash] = np.arange(next_id, next_id + len(clash), dtype=np.int64)
    return result, next_id + len(clash)


def _new_ids(base_ids: IntArray, side_ids: IntArray) -> IntArray:
    """The side's ids the base does not have (both sorted)."""
    if len(base_ids) == len(side_ids) and np.array_equal(base_ids, side_ids):
        return side_ids[:0]
    return side_ids[~_contains(base_ids, side_ids)]


def _known(ids: IntArray, *sorted_ids: IntArray) -> BoolArray:
    """Whether each id is in any of the sorted id arrays."""
    found = np.zeros(len(ids), dtype=bool)
    for known in sorted_ids:
        found |= _contains(known, ids)
    return found


def _renumber_child(
    base: MeshState, parent: MeshState, child: MeshState, top_ids: tuple[int, int] | None = None
) -> tuple[MeshState, IntArray, IntArray]:
    """The child with its new ids in the merged numbering, and the (old, new) pairs of the ids that changed.

    ``top_ids``: the largest vertex and cell ids of the whole states, when these are restricted to the change.
    """
    p_new_v, c_new_v = _new_ids(base.vertex_ids, parent.vertex_ids), _new_ids(base.vertex_ids, child.vertex_ids)
    p_new_c, c_new_c = _new_ids(base.cell_ids, parent.cell_ids), _new_ids(base.cell_ids, child.cell_ids)
    empty = np.empty((0, 2), dtype=np.int64)
    if (len(c_new_v) == 0 or len(p_new_v) == 0) and (len(c_new_c) == 0 or len(p_new_c) == 0):
        return child, empty, empty
    top_v = max([int(s.vertex_ids[-1]) for s in (base, parent, child) if s.n_vertices] + [-1])
    top_c = max([int(s.cell_ids[-1]) for s in (base, parent, child) if s.n_cells] + [-1])
    if top_ids is not None:
        top_v, top_c = max(top_v, int(top_ids[0])), max(top_c, int(top_ids[1]))

    # a column may be int64 on one side and float64 (NaN for a NULL) on the other: compare in a common type
    vtypes = {n: np.result_type(v, child.vertex_properties[n]) for n, v in parent.vertex_properties.items()}
    ctypes = {n: np.result_type(v, child.cell_properties[n]) for n, v in parent.cell_properties.items()}

    def vertex_keys(state: MeshState, ids: IntArray) -> list[bytes]:
        at = _positions(state.vertex_ids, ids)
        words = [_value_bits(state.vertices[at])] + [
            _value_bits(v[at].astype(vtypes[n])) for n, v in state.vertex_properties.items()
        ]
        return _row_keys(words)

    merged_v, _ = _renumber(
        c_new_v,
        vertex_keys(child, c_new_v),
        p_new_v,
        vertex_keys(parent, p_new_v),
        parent.vertex_ids,
        top_v + 1,
        "vertex",
        base.name,
    )
    vmap_old, vmap_new = c_new_v[merged_v != c_new_v], merged_v[merged_v != c_new_v]
    cells = child.cells
    if len(vmap_old):
        at = _positions(vmap_old, cells)
        cells = np.where(at >= 0, vmap_new[np.maximum(at, 0)], cells)

    def cell_keys(state: MeshState, state_cells: IntArray, ids: IntArray) -> list[bytes]:
        at = _positions(state.cell_ids, ids)
        canonical = _canonical_cells(state_cells[at]).view(np.uint64)
        return _row_keys([canonical] + [_value_bits(v[at].astype(ctypes[n])) for n, v in state.cell_properties.items()])

    merged_c, _ = _renumber(
        c_new_c,
        cell_keys(child, cells, c_new_c),
        p_new_c,
        cell_keys(parent, parent.cells, p_new_c),
        parent.cell_ids,
        top_c + 1,
        "cell",
        base.name,
    )
    cmap_old, cmap_new = c_new_c[merged_c != c_new_c], merged_c[merged_c != c_new_c]
    cell_ids = child.cell_ids
    if len(cmap_old):
        at = _positions(cmap_old, cell_ids)
        cell_ids = np.where(at >= 0, cmap_new[np.maximum(at, 0)], cell_ids)
    vertex_ids = child.vertex_ids
    if len(vmap_old):
        at = _positions(vmap_old, vertex_ids)
        vertex_ids = np.where(at >= 0, vmap_new[np.maximum(at, 0)], vertex_ids)
    vprops = dict(child.vertex_properties)
    if len(vmap_old) and "refid" in vprops:  # a GOCAD atom's refid is a vertex id (docs/merge.md): it follows it
        ref = vprops["refid"]
        values = np.nan_to_num(ref, nan=-1).astype(np.int64) if ref.dtype.kind == "f" else ref.astype(np.int64)
        at = _positions(vmap_old, values)
        vprops["refid"] = np.where(at >= 0, vmap_new[np.maximum(at, 0)], ref)
    # a consistent renaming of a valid state: only the order by id may need restoring
    vorder = slice(None) if _strictly_increasing(vertex_ids) else np.argsort(vertex_ids, kind="stable")
    corder = slice(None) if _strictly_increasing(cell_ids) else np.argsort(cell_ids, kind="stable")
    renumbered = _unchecked_state(
        child,
        vertex_ids[vorder],
        child.vertices[vorder],
        cell_ids[corder],
        cells[corder],
        {n: v[vorder] for n, v in vprops.items()},
        {n: v[corder] for n, v in child.cell_properties.items()},
    )
    return renumbered, np.stack([vmap_old, vmap_new], axis=1), np.stack([cmap_old, cmap_new], axis=1)


# ---------------------------------------------------------------- a merge restricted to the change


def changed_ids(base: MeshState, side: MeshState) -> tuple[IntArray, IntArray]:
    """(vertex ids, cell ids) of the rows ``side`` holds otherwise than ``base``: changed, added or removed.

    A row rewritten with the same content is no change (a rotated cell row
    neither). The rows whose storage versions differ between two revision
    sets are a superset of these, which :func:`change_neighbourhood` takes
    as well.
    """
    edit = _edit(base, side)
    return edit.changed_vertices, edit.changed_cells


def _cells_on(state: MeshState, vertex_ids: IntArray) -> IntArray:
    """Ids of the state's cells with a vertex among ``vertex_ids`` (sorted, unique)."""
    if len(vertex_ids) == 0 or state.n_cells == 0:
        return state.cell_ids[:0]
    return state.cell_ids[_cell_hits(vertex_ids, state.cells)]


def _corners(state: MeshState, cell_ids: IntArray) -> IntArray:
    """The vertex ids of the state's cells ``cell_ids`` (those it has)."""
    at = _positions(state.cell_ids, cell_ids)
    return state.cells[at[at >= 0]].ravel()


def change_neighbourhood(
    states: tuple[MeshState, ...], vertex_ids: npt.ArrayLike, cell_ids: npt.ArrayLike, *, rings: int = 2
) -> tuple[IntArray, IntArray]:
    """The rows a merge restricted to the change reads: the changed rows and one or two rings around them (docs/merge.md).

    From the ids of the rows changed on either side (vertices ``V0``, cells
    ``C0``), in every state of ``states`` (base, parent, child):

    - ``V1``: ``V0`` and the vertices of the cells ``C0``;
    - ``C1``: ``C0`` and the cells on a vertex of ``V1`` (the one-ring: the
      regions' margins are in it);
    - ``V2``: the vertices of ``C1`` (a region's vertices, its cells'
      corners: what the validity check looks around);
    - ``C2``: the cells on a vertex of ``V2`` (the two-ring: every cell the
      validity check counts);
    - ``V3``: ``V2`` and the vertices of ``C2`` (what those cells stand on).

    :func:`three_way_merge` of the three states restricted to ``(V3, C2)``
    (:func:`restrict_state`), given the whole states' largest ids, finds
    exactly the regions, conflicts, renumbering and validity of the whole
    states, and :func:`apply_solutions` gives the whole result's rows for
    any solution.

    With ``rings=1``, ``(V2, C1)``: enough for the regions, the renumbering,
    an automatic merge and the solutions ``parent``, ``child`` and ``base``.
    The validity check looks at the cells around the corners of the cells
    it takes; those it can find wrong (a duplicated or non-manifold cell, a
    cell on a removed vertex, a vertex left without cells) involve a changed
    cell or a removed vertex, whose cells all lie on ``V1`` (docs/merge.md),
    as long as every cell of ``C1`` no side changed stays: a manual mesh may
    drop one, and needs the second ring. The database reads one ring for the
    merges by region (:mod:`tgsis.db._merge_states`).

    Parameters
    ----------
    states : tuple of MeshState
        The states whose cells count (the whole ones here).
    vertex_ids, cell_ids : array_like of int
        ``V0`` and ``C0``: the ids of the changed rows (any superset of them).
    rings : int
        2 (any solution) or 1 (no manual mesh).

    Returns
    -------
    (V3, C2), or (V2, C1) with ``rings=1`` : int64 arrays, sorted, unique
    """
    if rings not in (1, 2):
        raise InvalidInputError(f"rings={rings!r}: the neighbourhood of a change is of 1 or 2 rings")
    v0 = np.unique(np.asarray(vertex_ids, dtype=np.int64))
    c0 = np.unique(np.asarray(cell_ids, dtype=np.int64))
    v1 = np.unique(np.concatenate([v0, *(_corners(s, c0) for s in states)]))
    c1 = np.unique(np.concatenate([c0, *(_cells_on(s, v1) for s in states)]))
    v2 = np.unique(np.concatenate([v1, *(_corners(s, c1) for s in states)]))
    if rings == 1:
        return v2, c1
    c2 = np.unique(np.concatenate([c1, *(_cells_on(s, v2) for s in states)]))
    v3 = np.unique(np.concatenate([v2, *(_corners(s, c2) for s in states)]))
    return v3, c2


def restrict_state(state: MeshState, vertex_ids: IntArray, cell_ids: IntArray) -> MeshState:
    """The state's rows of these ids (sorted, unique; ids it does not have are left out), properties with them.

    Raises
    ------
    InvalidGeometryError
        A kept cell stands on a vertex left out.
    """
    vat = _positions(state.vertex_ids, vertex_ids)
    vat = vat[vat >= 0]
    cat = _positions(state.cell_ids, cell_ids)
    cat = cat[cat >= 0]
    return MeshState(
        state.cell_size,
        state.vertex_ids[vat],
        state.vertices[vat],
        state.cell_ids[cat],
        state.cells[cat],
        {n: v[vat] for n, v in state.vertex_properties.items()},
        {n: v[cat] for n, v in state.cell_properties.items()},
        state.name,
    )


def largest_ids(*states: MeshState) -> tuple[int, int]:
    """The largest vertex id and the largest cell id of the states (-1 for none): :func:`three_way_merge`'s ``top_ids``."""
    return (
        max([int(s.vertex_ids[-1]) for s in states if s.n_vertices] + [-1]),
        max([int(s.cell_ids[-1]) for s in states if s.n_cells] + [-1]),
    )


# ---------------------------------------------------------------- regions


@dataclass(frozen=True)
class MergeRegion:
    """A connected set of changed vertices and cells (with their one-ring margin), see docs/merge.md.

    Ids are in the merged numbering (the child's renumbered new ids).

    Attributes
    ----------
    index : int
        Position in :attr:`MeshMerge.regions`; solutions are keyed by it.
    vertex_ids, cell_ids : (a,), (b,) int64
        Every vertex and cell of the region, margin included, ascending.
    parent_vertex_ids, parent_cell_ids, child_vertex_ids, child_cell_ids : int64 arrays
        The rows of the region each side changed (its edit), ascending.
    bounds : (2, 3) float64
        Bounding box of the region's vertices in the three states.
    parent_displacement, child_displacement : float
        Largest distance a vertex of the region moved on that side (0.0 when none).
    conflict : bool
        Both sides changed the region and their rows differ.
    """

    index: int
    vertex_ids: IntArray
    cell_ids: IntArray
    parent_vertex_ids: IntArray
    parent_cell_ids: IntArray
    child_vertex_ids: IntArray
    child_cell_ids: IntArray
    bounds: FloatArray
    parent_displacement: float
    child_displacement: float
    conflict: bool

    @property
    def sides(self) -> str:
        """``"parent"``, ``"child"`` or ``"both"``: which sides changed the region."""
        p = bool(len(self.parent_vertex_ids) or len(self.parent_cell_ids))
        c = bool(len(self.child_vertex_ids) or len(self.child_cell_ids))
        return "both" if p and c else ("parent" if p else "child")

    def __repr__(self) -> str:
        return (
            f"MergeRegion({self.index}, {self.sides}, conflict={self.conflict}, {len(self.vertex_ids)} vertices, "
            f"{len(self.cell_ids)} cells)"
        )


@dataclass(frozen=True)
class RegionDiscard:
    """What a region's solution throws away of one side's edit.

    Attributes
    ----------
    region : int
    solution : str
        ``parent``, ``child``, ``base``, ``average`` or ``manual``.
    side : str
        ``parent`` or ``child``: whose edit is lost.
    vertices, cells : int
        That side's changed rows the result does not hold as that side has them.
    max_displacement : float
        Largest distance between that side's position of a discarded vertex
        and the result's (vertices present in both; 0.0 when none).
    """

    region: int
    solution: str
    side: str
    vertices: int
    cells: int
    max_displacement: float


@dataclass(frozen=True)
class ResolvedMerge:
    """The merged state and what the solutions discarded (an automatic merge discards nothing).

    Attributes
    ----------
    state : MeshState
    discards : tuple of RegionDiscard
        One per (conflicting region, side) that loses something.
    """

    state: MeshState
    discards: tuple[RegionDiscard, ...]


@dataclass(frozen=True, eq=False)
class MeshMerge:
    """The result of :func:`three_way_merge`.

    Attributes
    ----------
    base, parent : MeshState
    child : MeshState
        The child with its new ids renumbered (below).
    regions : tuple of MergeRegion
        Every region either side changed, conflicts among them.
    child_vertex_renumbering, child_cell_renumbering : (r, 2) int64
        ``(child id, merged id)`` of the child's new rows whose id changed:
        the parent's new row with the same content (the same edit made twice),
        or a fresh id above every vertex (cell) id of the three states (the
        same id meaning something else on the parent).
    merged : ResolvedMerge or None
        The merge, when no region conflicts.
    """

    base: MeshState
    parent: MeshState
    child: MeshState
    regions: tuple[MergeRegion, ...]
    child_vertex_renumbering: IntArray
    child_cell_renumbering: IntArray
    merged: ResolvedMerge | None
    _region_of_vertex: tuple[IntArray, IntArray] = field(repr=False)  # (ids, region) of every region vertex
    _region_of_cell: tuple[IntArray, IntArray] = field(repr=False)

    @property
    def conflicts(self) -> tuple[MergeRegion, ...]:
        """The conflicting regions."""
        return tuple(r for r in self.regions if r.conflict)

    def resolve(self, solutions: Mapping[int, Solution]) -> ResolvedMerge:
        """:func:`apply_solutions` of this merge."""
        return apply_solutions(self, solutions)


def _footprint(base: MeshState, side: MeshState, edit: _Edit, margin_cells: IntArray) -> tuple[IntArray, IntArray]:
    """(vertex ids, cell ids) of a side's edit grown by the one-ring margin."""
    cells = np.union1d(edit.changed_cells, margin_cells)
    corner_rows = [
        state.cells[at[at >= 0]].ravel()
        for state in (base, side)
        for at in [_positions(state.cell_ids, edit.topology_cells)]
    ]
    vertices = np.union1d(edit.changed_vertices, np.concatenate(corner_rows))
    return vertices, cells


def _incidences(base: MeshState, side: MeshState, vertices: IntArray, cells: IntArray) -> tuple[IntArray, IntArray]:
    """(cell id, vertex id) pairs of the footprint's cells, in the base and the side, both ends in the footprint."""
    pairs_c, pairs_v = [], []
    for state in (base, side):
        at = _positions(state.cell_ids, cells)
        present = at >= 0
        rows = state.cells[at[present]]
        owner = np.repeat(cells[present], state.cell_size)
        corner = rows.ravel()
        inside = _contains(vertices, corner)
        pairs_c.append(owner[inside])
        pairs_v.append(corner[inside])
    return np.concatenate(pairs_c), np.concatenate(pairs_v)


def state_rows_equal(
    a: MeshState, b: MeshState, vertex_ids: IntArray, cell_ids: IntArray
) -> tuple[BoolArray, BoolArray]:
    """Per id, whether the two states hold the same row (both without it counts as the same)."""
    pa, pb = _positions(a.vertex_ids, vertex_ids), _positions(b.vertex_ids, vertex_ids)
    v_same = (pa < 0) & (pb < 0)
    both = np.flatnonzero((pa >= 0) & (pb >= 0))
    v_same[both] = a._vertex_rows_equal(b, pa[both], pb[both])[0]
    ca, cb = _positions(a.cell_ids, cell_ids), _positions(b.cell_ids, cell_ids)
    c_same = (ca < 0) & (cb < 0)
    both = np.flatnonzero((ca >= 0) & (cb >= 0))
    c_same[both] = a._cell_rows_equal(b, ca[both], cb[both])[0]
    return v_same, c_same


def _check_comparable(base: MeshState, parent: MeshState, child: MeshState) -> None:
    for state in (parent, child):
        if state.cell_size != base.cell_size:
            raise InvalidGeometryError(
                f"{base.name}: cannot merge cells of {base.cell_size} and {state.cell_size} vertices "
                f"({state.name}): a change of geometry type is an object-level conflict"
            )
        for what, mine, theirs in (
            ("vertex", base.vertex_properties, state.vertex_properties),
            ("cell", base.cell_properties, state.cell_properties),
        ):
            if list(mine) != list(theirs) or any(mine[n].shape[1:] != theirs[n].shape[1:] for n in mine):
                raise InvalidPropertyError(
                    f"{base.name}: the {what} properties differ between the states "
                    f"({sorted(mine)} and {sorted(theirs)} of {state.name})",
                    hint="give the three states the same property columns (a value the database does not have as NaN)",
                )


def three_way_merge(
    base: MeshState, parent: MeshState, child: MeshState, *, top_ids: tuple[int, int] | None = None
) -> MeshMerge:
    """Merge the parent's and the child's edits of one object, both made from ``base``.

    Parameters
    ----------
    base, parent, child : MeshState
        The object at the common base, in the parent and in the child; same
        cell size and property columns. Either the whole object, or, with
        ``top_ids``, the three states restricted to the change and its rings
        (:func:`change_neighbourhood`, :func:`restrict_state`): the regions,
        conflicts, renumbering and validity are then exactly those of the
        whole states, and the merged state (and a solved one, for the
        solutions :func:`change_neighbourhood` says) is the whole merge
        restricted to the same rows.
    top_ids : (int, int), optional
        The largest vertex id and the largest cell id of the three whole
        states (-1 for none), for states restricted to the change: the
        child's new ids that clash are renumbered above them.

    Returns
    -------
    MeshMerge
        Its regions, conflicts among them, the child's renumbered ids and,
        when nothing conflicts, the merged state (validity checked).

    Raises
    ------
    InvalidGeometryError, InvalidPropertyError
        States of different cell sizes or property columns.
    InvalidMergeError
        No region conflicts but the merged mesh would not be valid.
    """
    _check_comparable(base, parent, child)
    child, vertex_renumbering, cell_renumbering = _renumber_child(base, parent, child, top_ids)
    edits = (_edit(base, parent), _edit(base, child))

    # the one-ring margin of both sides in one pass over the base's cells
    shape_ids = np.union1d(edits[0].shape_vertices, edits[1].shape_vertices)
    shape_flags = _contains(edits[0].shape_vertices, shape_ids).astype(np.uint8)
    shape_flags |= _contains(edits[1].shape_vertices, shape_ids).astype(np.uint8) * np.uint8(2)
    cell_flags = np.zeros(base.n_cells, dtype=np.uint8)
    for j in range(base.cell_size):  # column by column: an or-reduce over rows of 3 is slower
        cell_flags |= _flags(shape_ids, shape_flags, base.cells[:, j])
    touched = np.flatnonzero(cell_flags)
    footprints = [
        _footprint(base, side, edit, base.cell_ids[touched[(cell_flags[touched] & bit) != 0]])
        for side, edit, bit in ((parent, edits[0], 1), (child, edits[1], 2))
    ]
    # margins of cells a side added around its own shape changes: they are changed cells already

    node_v = np.union1d(footprints[0][0], footprints[1][0])
    node_c = np.union1d(footprints[0][1], footprints[1][1])
    regions, region_of_v, region_of_c = _regions(base, parent, child, edits, footprints, node_v, node_c)
    merge = MeshMerge(
        base,
        parent,
        child,
        regions,
        vertex_renumbering,
        cell_renumbering,
        None,
        (node_v, region_of_v),
        (node_c, region_of_c),
    )
    if not merge.conflicts:
        object.__setattr__(merge, "merged", apply_solutions(merge, {}))
    return merge


def _regions(
    base: MeshState,
    parent: MeshState,
    child: MeshState,
    edits: tuple[_Edit, _Edit],
    footprints: list[tuple[IntArray, IntArray]],
    node_v: IntArray,
    node_c: IntArray,
) -> tuple[tuple[MergeRegion, ...], IntArray, IntArray]:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nv, n = len(node_v), len(node_v) + len(node_c)
    if n == 0:
        return (), node_v, node_c
    rows, cols = [], []
    for side, (fv, fc) in zip((parent, child), footprints):
        pc, pv = _incidences(base, side, fv, fc)
        rows.append(nv + _positions(node_c, pc))
        cols.append(_positions(node_v, pv))
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r), dtype=np.int8), (r, c)), shape=(n, n)).tocsr()
    count, labels = connected_components(graph, directed=False)
    label_v, label_c = labels[:nv].astype(np.int64), labels[nv:].astype(np.int64)

    # conflicts: both sides changed the region and a row differs between them
    def per_region(mask_v: BoolArray, mask_c: BoolArray) -> BoolArray:
        hits = np.bincount(label_v[mask_v], minlength=count) + np.bincount(label_c[mask_c], minlength=count)
        return np.asarray(hits > 0, dtype=bool)

    changed = [(_contains(e.changed_vertices, node_v), _contains(e.changed_cells, node_c)) for e in edits]
    has_parent, has_child = per_region(*changed[0]), per_region(*changed[1])
    v_same, c_same = state_rows_equal(parent, child, node_v, node_c)
    differs = per_region(~v_same, ~c_same)
    conflict = has_parent & has_child & differs

    # boxes over the three states, displacements per side: grouped by region with reduceat
    boxes = np.full((count, 2, 3), np.nan)
    displacement = np.zeros((2, count))
    for state in (base, parent, child):  # the region's vertices and the corners of its cells
        at = _positions(state.vertex_ids, node_v)
        present = at >= 0
        cat = _positions(state.cell_ids, node_c)
        cpresent = cat >= 0
        corners = _positions(state.vertex_ids, state.cells[cat[cpresent]].ravel())
        xyz = np.concatenate([state.vertices[at[present]], state.vertices[corners]])
        lab = np.concatenate([label_v[present], np.repeat(label_c[cpresent], state.cell_size)])
        np.fmin.at(boxes[:, 0], lab, xyz)
        np.fmax.at(boxes[:, 1], lab, xyz)
    for s, (side, edit) in enumerate(zip((parent, child), edits)):
        moved = edit.moved_vertices
        if len(moved):
            d = np.linalg.norm(
                side.vertices[_positions(side.vertex_ids, moved)] - base.vertices[_positions(base.vertex_ids, moved)],
                axis=1,
            )
            np.maximum.at(displacement[s], label_v[_positions(node_v, moved)], d)

    order_v, order_c = np.argsort(label_v, kind="stable"), np.argsort(label_c, kind="stable")
    split_v = np.searchsorted(label_v[order_v], np.arange(count + 1))
    split_c = np.searchsorted(label_c[order_c], np.arange(count + 1))
    result = []
    for i in range(count):
        sv, sc = order_v[split_v[i] : split_v[i + 1]], order_c[split_c[i] : split_c[i + 1]]
        result.append(
            MergeRegion(
                i,
                node_v[sv],
                node_c[sc],
                node_v[sv[changed[0][0][sv]]],
                node_c[sc[changed[0][1][sc]]],
                node_v[sv[changed[1][0][sv]]],
                node_c[sc[changed[1][1][sc]]],
                boxes[i],
                float(displacement[0, i]),
                float(displacement[1, i]),
                bool(conflict[i]),
            )
        )
    return tuple(result), label_v, label_c


# ---------------------------------------------------------------- solutions


Table: TypeAlias = "tuple[IntArray, npt.NDArray[Any], dict[str, npt.NDArray[Any]]]"


def _replace_rows(table: Table, drop: IntArray, added: list[Table]) -> Table:
    """The rows of ``table`` (ids ascending) without ids ``drop`` (few), with the ``added`` rows at their places.

    When the added ids are the dropped ones (moves, property changes) the rows
    are rewritten in place in one copy; else the few rows are inserted, never
    sorting the many.
    """
    ids, rows, props = table
    at = _positions(ids, drop)
    at = np.unique(at[at >= 0])
    new_ids = np.concatenate([a[0] for a in added])
    order = np.argsort(new_ids, kind="stable")
    new_ids = new_ids[order]
    new_rows = np.concatenate([a[1] for a in added])[order]
    new_props = {n: np.concatenate([a[2][n] for a in added])[order] for n in props}
    # a column may be int64 in one state and float64 (NaN for a NULL) in another: never cast a value down
    props = {n: v.astype(np.result_type(v, new_props[n]), copy=False) for n, v in props.items()}
    if len(at) == len(new_ids) and np.array_equal(ids[at], new_ids):
        out_rows, out_props = rows.copy(), {n: v.copy() for n, v in props.items()}
        out_rows[at] = new_rows
        for n in props:
            out_props[n][at] = new_props[n]
        return ids.copy(), out_rows, out_props
    keep = np.ones(len(ids), dtype=bool)
    keep[at] = False
    kept = ids[keep]
    where = np.searchsorted(kept, new_ids)
    return (
        np.insert(kept, where, new_ids),
        np.insert(rows[keep], where, new_rows, axis=0),
        {n: np.insert(v[keep], where, new_props[n], axis=0) for n, v in props.items()},
    )


def _take_rows(
    into: MeshState, drop_v: IntArray, drop_c: IntArray, sources: list[tuple[MeshState, IntArray, IntArray]]
) -> MeshState:
    """``into`` without the rows ``drop_*``, with the rows of these ids taken from each source (when it has them)."""
    added_v: list[Table] = []
    added_c: list[Table] = []
    for source, vids, cids in sources:
        at = _positions(source.vertex_ids, vids)
        at = at[at >= 0]
        added_v.append(
            (source.vertex_ids[at], source.vertices[at], {n: v[at] for n, v in source.vertex_properties.items()})
        )
        at = _positions(source.cell_ids, cids)
        at = at[at >= 0]
        added_c.append((source.cell_ids[at], source.cells[at], {n: v[at] for n, v in source.cell_properties.items()}))
    vids, xyz, vprops = _replace_rows((into.vertex_ids, into.vertices, dict(into.vertex_properties)), drop_v, added_v)
    cids, cells, cprops = _replace_rows((into.cell_ids, into.cells, dict(into.cell_properties)), drop_c, added_c)
    return _unchecked_state(into, vids, xyz, cids, cells, vprops, cprops)


def _unchecked_state(
    like: MeshState,
    vids: IntArray,
    xyz: FloatArray,
    cids: IntArray,
    cells: IntArray,
    vprops: dict[str, npt.NDArray[Any]],
    cprops: dict[str, npt.NDArray[Any]],
) -> MeshState:
    """A state from rows already checked (sorted, unique: checked by _check_valid), without the constructor's passes."""
    state = object.__new__(MeshState)
    for name, value in (
        ("cell_size", like.cell_size),
        ("vertex_ids", vids),
        ("vertices", xyz),
        ("cell_ids", cids),
        ("cells", cells),
        ("vertex_properties", vprops),
        ("cell_properties", cprops),
        ("name", like.name),
    ):
        object.__setattr__(state, name, value)
    return state


def _solution_name(solution: Solution) -> str:
    return "manual" if isinstance(solution, MeshState) else str(solution)


def apply_solutions(
    merge: MeshMerge, solutions: Mapping[int, Solution], *, names: Mapping[int, str] | None = None
) -> ResolvedMerge:
    """The merged state with each conflicting region solved, and what the solutions discard.

    Parameters
    ----------
    merge : MeshMerge
    solutions : mapping of region index to solution
        One per conflicting region, none for another: ``"parent"`` (the
        parent's rows of the region), ``"child"``, ``"base"``, or a
        :class:`MeshState` (manual: its rows with ids of the region or ids no
        state has are the region's rows; rows of other ids it holds must equal
        the merge's). ``average`` is a manual state the caller builds
        (docs/merge.md).
    names : mapping of region index to str, optional
        What a :class:`MeshState` solution is called in the discards
        (:attr:`RegionDiscard.solution`): ``"average"`` for an average shape;
        ``"manual"`` when not given.

    Returns
    -------
    ResolvedMerge

    Raises
    ------
    UnsolvedConflictsError
        A conflicting region without a solution.
    InvalidInputError
        A solution for a region that does not conflict (it would drop the
        other side's edit there), an unknown region or solution, a manual
        state of another cell size or property columns, or one that changes
        rows outside its region.
    InvalidMergeError
        The result is not a valid mesh (the message names the ids).
    """
    name = merge.base.name
    conflicts = {r.index for r in merge.conflicts}
    unsolved = sorted(conflicts - set(solutions))
    if unsolved:
        raise UnsolvedConflictsError(
            f"{name}: regions {ids_text(unsolved)} changed on both sides have no solution",
            hint="give each conflicting region parent, child, base or a manual mesh",
        )
    for index, solution in solutions.items():
        if not isinstance(index, (int, np.integer)) or isinstance(index, bool):  # "0" from JSON, True == 1
            raise InvalidInputError(f"{name}: region {index!r} is not a region: a region is given by its index")
        if index not in conflicts:
            raise InvalidInputError(
                f"{name}: region {index} is {'not a region' if not 0 <= index < len(merge.regions) else 'no conflict'}"
                ": only a conflicting region takes a solution (the other side's edits elsewhere are kept)"
            )
        if not (isinstance(solution, MeshState) or solution in ("parent", "child", "base")):
            raise InvalidInputError(f"{name}: region {index}: unknown solution {solution!r}")
        if isinstance(solution, MeshState):
            _check_comparable(merge.base, solution, solution)

    ids_v, region_v = merge._region_of_vertex
    ids_c, region_c = merge._region_of_cell
    # automatic regions one the child changed take its rows; everything else starts as the parent's
    from_child = {r.index for r in merge.regions if not r.conflict and r.sides == "child"}
    by_source: dict[str, list[int]] = {"child": sorted(from_child), "base": [], "manual": []}
    for index, solution in solutions.items():
        if solution != "parent":
            by_source[_solution_name(solution)].append(index)

    def ids_of(indices: list[int]) -> tuple[IntArray, IntArray]:
        wanted = np.isin(region_v, indices), np.isin(region_c, indices)
        return ids_v[wanted[0]], ids_c[wanted[1]]

    child_v, child_c = ids_of(by_source["child"])
    base_v, base_c = ids_of(by_source["base"])
    manual_v, manual_c = ids_of(by_source["manual"])
    drop_v = np.concatenate([child_v, base_v, manual_v])
    drop_c = np.concatenate([child_c, base_c, manual_c])
    sources = [(merge.child, child_v, child_c), (merge.base, base_v, base_c)]
    state = _take_rows(merge.parent, drop_v, drop_c, sources)
    if by_source["manual"]:  # ids no state has: a manual mesh's new rows
        states = (merge.base, merge.parent, merge.child)
    manual_new: list[tuple[IntArray, IntArray]] = []
    for index in by_source["manual"]:
        manual = solutions[index]
        assert isinstance(manual, MeshState)
        in_v, in_c = ids_of([index])
        take_v = _contains(in_v, manual.vertex_ids) | ~_known(manual.vertex_ids, *(s.vertex_ids for s in states))
        take_c = _contains(in_c, manual.cell_ids) | ~_known(manual.cell_ids, *(s.cell_ids for s in states))
        # rows of another manually solved region are that region's solution's to give (one whole mesh may solve all)
        elsewhere_v = ~take_v & ~_contains(manual_v, manual.vertex_ids)
        elsewhere_c = ~take_c & ~_contains(manual_c, manual.cell_ids)
        _check_outside_rows(name, index, manual, state, elsewhere_v, elsewhere_c)
        manual_new.append(
            (
                manual.vertex_ids[take_v & ~_contains(in_v, manual.vertex_ids)],
                manual.cell_ids[take_c & ~_contains(in_c, manual.cell_ids)],
            )
        )
        state = _take_rows(
            state,
            np.empty(0, np.int64),
            np.empty(0, np.int64),
            [(manual, manual.vertex_ids[take_v], manual.cell_ids[take_c])],
        )
    _check_valid(merge, state, drop_v, drop_c, manual_new)
    return ResolvedMerge(state, _discards(merge, solutions, state, names or {}))


def _check_outside_rows(
    name: str, index: int, manual: MeshState, state: MeshState, outside_v: BoolArray, outside_c: BoolArray
) -> None:
    """A manual state's rows outside its region must be the merge's own (it may hold the whole object)."""
    ov, oc = manual.vertex_ids[outside_v], manual.cell_ids[outside_c]
    v_same, c_same = state_rows_equal(manual, state, ov, oc)
    if not (v_same.all() and c_same.all()):
        raise InvalidInputError(
            f"{name}: the manual mesh of region {index} changes rows outside the region: vertices "
            f"{ids_text(ov[~v_same]) or 'none'}, cells {ids_text(oc[~c_same]) or 'none'}",
            hint="a manual mesh replaces its region's rows (and may add rows of new ids); solve the other regions "
            "on their own",
        )


def _check_valid(
    merge: MeshMerge, state: MeshState, drop_v: IntArray, drop_c: IntArray, manual_new: list[tuple[IntArray, IntArray]]
) -> None:
    """Refuse a merged state that is invalid where neither the base nor a side was; only the changed rows are looked at.

    Rows not replaced are the parent's, which was valid, so only the rows taken
    from elsewhere, and the vertices they and the dropped rows touch, can break it.
    """
    name, k, word = merge.base.name, state.cell_size, _CELL_WORDS[state.cell_size]
    for what, ids in (("vertex", state.vertex_ids), (word, state.cell_ids)):
        if not _strictly_increasing(ids):
            repeated = np.unique(ids[1:][ids[1:] <= ids[:-1]])
            raise InvalidMergeError(f"{name}: the merge would give two {what} rows the id {ids_text(repeated)}")
    new_c = np.union1d(drop_c, np.concatenate([c for _, c in manual_new] + [np.empty(0, np.int64)]))
    new_v = np.union1d(drop_v, np.concatenate([v for v, _ in manual_new] + [np.empty(0, np.int64)]))
    at = _positions(state.cell_ids, new_c)
    taken_cells = state.cells[at[at >= 0]]
    taken_ids = state.cell_ids[at[at >= 0]]
    # the vertices whose cells may have changed: of the taken cells, of the parent's cells they replace, new ones
    replaced = merge.parent.cells[_positions(merge.parent.cell_ids, new_c)[_contains(merge.parent.cell_ids, new_c)]]
    near = np.unique(np.concatenate([taken_cells.ravel(), replaced.ravel(), new_v]))

    missing = ~_contains(state.vertex_ids, taken_cells)
    gone_v = near[~_contains(state.vertex_ids, near)]
    lost = _cell_hits(gone_v, state.cells) if len(gone_v) else np.zeros(state.n_cells, dtype=bool)
    if missing.any() or lost.any():
        bad = np.union1d(taken_ids[missing.any(axis=1)], state.cell_ids[lost])
        rows = state.cells[_positions(state.cell_ids, bad)]
        raise InvalidMergeError(
            f"{name}: the merge would keep {word}s {ids_text(bad)} on vertices "
            f"{ids_text(np.unique(rows[~_contains(state.vertex_ids, rows)]))} that it removes",
            hint="one side removed vertices the other side's cells use: solve the region with one side's rows",
        )

    if "refid" in state.vertex_properties:  # GOCAD atoms: a vertex id, which must still be there
        ref = state.vertex_properties["refid"]
        if ref.dtype.kind == "f":  # a value no int64 holds (NaN, 1e19) is no vertex: the writer refuses it by name
            ref = np.where(np.isfinite(ref) & (np.abs(ref) < 2.0**63), ref, -1).astype(np.int64)
        else:
            ref = ref.astype(np.int64)
        dangling_ref = (ref >= 0) & ~_contains(state.vertex_ids, ref)
        if dangling_ref.any():  # the parent's own rows are excused where the parent itself lacks the vertex
            # (it is the state merged into); an unchanged atom whose vertex the merge removes is not
            at = np.flatnonzero(dangling_ref)
            v_same, _ = state_rows_equal(state, merge.parent, state.vertex_ids[at], np.empty(0, np.int64))
            dangling_ref[at[v_same & ~_contains(merge.parent.vertex_ids, ref[at])]] = False
        if dangling_ref.any():
            raise InvalidMergeError(
                f"{name}: the merge would keep vertices {ids_text(state.vertex_ids[dangling_ref])}, atoms (refid) "
                f"that refer to vertices {ids_text(np.unique(ref[dangling_ref]))}, which it removes",
                hint="one side removed vertices the other side's atoms refer to: solve the region with one side's rows",
            )

    def local(s: MeshState) -> tuple[IntArray, IntArray]:
        """(cell ids, cells) of a state's cells on any vertex near the change."""
        if len(near) == 0 or s.n_cells == 0:
            return s.cell_ids[:0], s.cells[:0]
        hit = _cell_hits(near, s.cells)
        return s.cell_ids[hit], s.cells[hit]

    mine_ids, mine = local(state)
    sides_found: list[tuple[IntArray, IntArray]] = []

    def sides() -> list[tuple[IntArray, IntArray]]:  # the three states near the change: only to excuse a finding
        if not sides_found:
            sides_found.extend([local(merge.parent), local(merge.child), local(merge.base)])
        return sides_found

    # duplicated cells (the same vertices, any order) among the taken ones
    keys = np.sort(mine, axis=1)
    _refuse_new_excess(
        name,
        f"duplicated {word}s (the same vertices)",
        keys,
        mine_ids,
        taken_ids,
        lambda: [np.sort(c, axis=1) for _, c in sides()],
        1,
    )
    if k >= 3:  # an edge of triangles, a face of tetrahedra, shared by more than two cells
        what = "edge" if k == 3 else "face"
        faces, owners = _facets(mine, mine_ids)
        _refuse_new_excess(
            name,
            f"non-manifold {what}s (in more than two {word}s)",
            faces,
            owners,
            taken_ids,
            lambda: [_facets(c, i)[0] for i, c in sides()],
            2,
        )
    # vertices near the change left without cells, which no state leaves so
    used = np.unique(mine)
    dangling = near[_contains(state.vertex_ids, near) & ~_contains(used, near)]
    if len(dangling):
        for s, (_, c) in zip((merge.parent, merge.child, merge.base), sides()):
            unused_there = _contains(s.vertex_ids, dangling) & ~_contains(np.unique(c), dangling)
            dangling = dangling[~unused_there]
        if len(dangling):
            raise InvalidMergeError(
                f"{name}: the merge would leave vertices {ids_text(dangling)} without {word}s, which no state does",
                hint="solve the region with one side's rows",
            )


def _facets(cells: IntArray, ids: IntArray) -> tuple[IntArray, IntArray]:
    """Sorted (k-1)-vertex facets of the cells (edges of triangles, faces of tetrahedra) and their cell ids."""
    k = cells.shape[1]
    parts = [np.delete(cells, i, axis=1) for i in range(k)]
    return np.sort(np.concatenate(parts), axis=1), np.tile(ids, k)


def _counts(keys: IntArray) -> tuple[IntArray, IntArray]:
    if len(keys) == 0:
        return keys, np.empty(0, dtype=np.int64)
    unique, counts = np.unique(keys, axis=0, return_counts=True)
    return unique, counts


def _refuse_new_excess(
    name: str,
    what: str,
    keys: IntArray,
    owners: IntArray,
    taken: IntArray,
    side_keys: Callable[[], list[IntArray]],
    limit: int,
) -> None:
    """Refuse keys held by more than ``limit`` cells, one of them taken, that no state (base, sides) has so often."""
    unique, counts = _counts(keys)
    over = unique[counts > limit]
    if len(over) == 0:
        return

    def rows_in(rows: IntArray, table: IntArray) -> BoolArray:
        if len(table) == 0 or len(rows) == 0:
            return np.zeros(len(rows), dtype=bool)
        both = np.concatenate([table, rows])
        _, inverse = np.unique(both, axis=0, return_inverse=True)
        return np.isin(inverse.ravel()[len(table) :], inverse.ravel()[: len(table)])

    over = over[rows_in(over, keys[_contains(np.sort(taken), owners)])]  # only what a taken cell is part of
    if len(over) == 0:
        return
    for side in side_keys():
        su, sc = _counts(side)
        over = over[~rows_in(over, su[sc > limit])]
    bad_rows = rows_in(keys, over)
    bad_owners = np.intersect1d(owners[bad_rows], taken)
    if len(bad_owners):
        raise InvalidMergeError(
            f"{name}: the merge would make {what} that no state has: vertex ids "
            f"{ids_text([str(tuple(r)) for r in over.tolist()])}, cells {ids_text(np.unique(owners[bad_rows]))}",
            hint="solve the region with one side's rows, or give a manual mesh without them",
        )


def _discards(
    merge: MeshMerge, solutions: Mapping[int, Solution], state: MeshState, names: Mapping[int, str]
) -> tuple[RegionDiscard, ...]:
    """Per solved region and side: that side's changed rows the result does not hold as the side does."""
    found = []
    for index in sorted(solutions):
        region, solution = merge.regions[index], solutions[index]
        for side_name, side, vids, cids in (
            ("parent", merge.parent, region.parent_vertex_ids, region.parent_cell_ids),
            ("child", merge.child, region.child_vertex_ids, region.child_cell_ids),
        ):
            v_same, c_same = state_rows_equal(side, state, vids, cids)
            lost_v = vids[~v_same]
            ps, pm = _positions(side.vertex_ids, lost_v), _positions(state.vertex_ids, lost_v)
            both = (ps >= 0) & (pm >= 0)
            moved = side.vertices[ps[both]] - state.vertices[pm[both]]
            largest = float(np.linalg.norm(moved, axis=1).max()) if len(moved) else 0.0
            if len(lost_v) or (~c_same).any():
                found.append(
                    RegionDiscard(
                        index,
                        names.get(index, "manual") if isinstance(solution, MeshState) else str(solution),
                        side_name,
                        len(lost_v),
                        int((~c_same).sum()),
                        largest,
                    )
                )
    return tuple(found)
