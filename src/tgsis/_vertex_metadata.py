"""Metadata entries that name vertices by index: GOCAD vertex flags and property control nodes, renumbered.

``metadata["gocad_vertex_flags"]`` (``{flag: [[start, stop], ...]}``, ranges of
vertex indices) and ``metadata["gocad_property_control_nodes"]`` (``{file
name: [vertex index, ...]}``) name vertices by their place in the mesh. When
the vertices are renumbered, they must follow, or they name other vertices
without any error:

* the spatial order of ids at upload (:func:`tgsis.mesh.spatial_order`)
  permutes the vertices;
* storage keeps them **by vertex id** (``tgsis.vrtx.vrtxid``), as it keeps
  atoms (``tgsis.atom``): a check-in by difference gives vertices inserted in
  the middle of a file ids above every id the object had, so a fetched mesh
  (vertices in id order) has them at the end, and a check-in that deletes
  vertices shifts the places of the others. Written by id, read back as places
  in the fetched mesh, the entries name the same vertices in every version.

An upload numbers vertices 0..n-1 in the mesh's order, so for every object
stored before this module the indices stored were ids already.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGeometryError

__all__ = ["FLAGS", "CONTROL_NODES", "vertex_indices", "renumbered", "places_of_ids"]

log = logging.getLogger(__name__)

IntArray = npt.NDArray[np.int64]

FLAGS = "gocad_vertex_flags"
CONTROL_NODES = "gocad_property_control_nodes"

_HINT = "correct or remove that metadata entry"


def vertex_indices(value: Any, n: int, key: str, name: str | None, why: str, hint: str = _HINT) -> IntArray:
    """A metadata list of vertex indices as int64, each in 0..n-1.

    Raises
    ------
    InvalidGeometryError
        Something else than such indices (``why`` says what needed them).
    """
    array = np.asarray(value if isinstance(value, (list, tuple)) else [None])
    if array.size and (array.dtype.kind not in "iu" or int(array.min()) < 0 or int(array.max()) >= n):
        raise InvalidGeometryError(
            f"metadata[{key!r}] of {name or 'the mesh'} holds something else than vertex indices 0..{n - 1}: {why}",
            hint=hint,
        )
    return array.astype(np.int64).reshape(-1) if array.size else np.empty(0, dtype=np.int64)


def _flag_ranges(ranges: Any, n: int, name: str | None, why: str, hint: str = _HINT) -> npt.NDArray[np.int64]:
    """``[[start, stop], ...]`` as an (r, 2) array of ranges within 0..n, each start <= stop."""
    flat = vertex_indices(ranges, n + 1, FLAGS, name, why, hint)
    bounds = flat.reshape(-1, 2) if len(flat) % 2 == 0 else np.empty((0, 2), dtype=np.int64)
    if len(bounds) * 2 != len(flat) or bool((bounds[:, 0] > bounds[:, 1]).any()):
        raise InvalidGeometryError(
            f"metadata[{FLAGS!r}] of {name or 'the mesh'} holds something else than "
            f"[start, stop] ranges of vertex indices 0..{n}: {why}",
            hint=hint,
        )
    return bounds


def _runs(values: IntArray) -> list[list[int]]:
    """Sorted distinct indices as ``[[start, stop], ...]`` runs of consecutive ones."""
    if len(values) == 0:
        return []
    breaks = np.flatnonzero(np.diff(values) != 1) + 1
    starts = np.concatenate([values[:1], values[breaks]])
    stops = np.concatenate([values[breaks - 1], values[-1:]]) + 1
    return [[int(a), int(b)] for a, b in zip(starts, stops)]


def renumbered(
    metadata: Mapping[str, Any], n: int, new_of_old: IntArray, name: str | None, why: str, hint: str = _HINT
) -> dict[str, Any]:
    """The metadata with the vertex index ``i`` of its flags and control nodes replaced by ``new_of_old[i]``.

    Parameters
    ----------
    metadata : mapping
        A mesh's metadata (other entries are copied as they are).
    n : int
        The number of vertices the indices are places in.
    new_of_old : (n,) int64
        The new number of each vertex (distinct, >= 0): a permutation, or the
        vertex ids of a check-in.
    name, why, hint : str
        Named in the error.

    Raises
    ------
    InvalidGeometryError
        An entry holds something else than vertex places of the mesh.
    """
    meta = dict(metadata)
    flags = meta.get(FLAGS)
    if isinstance(flags, Mapping) and flags:
        result: dict[str, list[list[int]]] = {}
        for flag, ranges in flags.items():
            bounds = _flag_ranges(ranges, n, name, why, hint)
            depth = np.zeros(n + 1, dtype=np.int64)  # ranges may overlap: count how many cover each vertex
            np.add.at(depth, bounds[:, 0], 1)
            np.add.at(depth, bounds[:, 1], -1)
            runs = _runs(np.sort(new_of_old[np.cumsum(depth)[:n] > 0]))
            if runs:
                result[str(flag)] = runs
        meta[FLAGS] = result
    nodes = meta.get(CONTROL_NODES)
    if isinstance(nodes, Mapping):
        meta[CONTROL_NODES] = {
            key: sorted(int(v) for v in new_of_old[vertex_indices(values, n, CONTROL_NODES, name, why, hint)])
            for key, values in nodes.items()
        }
    return meta


def places_of_ids(metadata: Mapping[str, Any], vertex_ids: IntArray, name: str | None = None) -> dict[str, Any]:
    """Stored flags and control nodes (by vertex id) as places in a mesh whose vertices have ``vertex_ids``.

    ``vertex_ids`` (n,) int64 ascending: the mesh's vertices are in id order,
    as every download gives them. A range of ids is the range of places of the
    ids within it; an id no vertex has (deleted since) names nothing and is
    left out. An entry that holds something else than ids (written by hand)
    is given back as stored, with a warning: it cannot be placed.
    """
    meta = dict(metadata)
    flags = meta.get(FLAGS)
    if isinstance(flags, Mapping) and flags:
        result: dict[str, list[list[int]]] = {}
        try:
            for flag, ranges in flags.items():
                bounds = _flag_ranges(ranges, 2**62, name, "it cannot be placed")
                places = np.stack(
                    [np.searchsorted(vertex_ids, bounds[:, 0]), np.searchsorted(vertex_ids, bounds[:, 1])], 1
                )
                depth = np.zeros(len(vertex_ids) + 1, dtype=np.int64)
                np.add.at(depth, places[:, 0], 1)
                np.add.at(depth, places[:, 1], -1)
                runs = _runs(np.flatnonzero(np.cumsum(depth)[: len(vertex_ids)] > 0).astype(np.int64))
                if runs:
                    result[str(flag)] = runs
            meta[FLAGS] = result
        except InvalidGeometryError as exc:
            log.warning("%s; given back as stored", exc.message)
    nodes = meta.get(CONTROL_NODES)
    if isinstance(nodes, Mapping):
        try:
            placed: dict[str, list[int]] = {}
            for key, values in nodes.items():
                ids = vertex_indices(values, 2**62, CONTROL_NODES, name, "it cannot be placed")
                at = np.searchsorted(vertex_ids, ids)
                found = at < len(vertex_ids)
                found[found] = vertex_ids[at[found]] == ids[found]
                placed[key] = sorted(int(v) for v in at[found])
            meta[CONTROL_NODES] = placed
        except InvalidGeometryError as exc:
            log.warning("%s; given back as stored", exc.message)
    return meta
