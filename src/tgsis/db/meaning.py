"""What a file means, kept with a stored geometry: z convention, coordinate system, colour, format facts, atoms, parts.

A reader leaves these in ``mesh.metadata`` (and the ``part`` cell property);
the write path stores them and the read path hands them back, so that
importing a file and exporting it from the database gives the same model:

* ``metadata["zpositive"]`` → ``tgsis.geometry.zpositive`` (``Elevation`` or
  ``Depth``). **Stored z is always elevation** (up positive): the z of a Depth
  geometry is negated on the way in and back on the way out. Negating a double
  only flips its sign bit, so the round trip is bit-exact (``-0.0`` too), and
  every query (bounding boxes, snapshots, comparisons, interpolation) compares
  like with like without knowing conventions.
* ``metadata["gocad_coordinate_system"]`` (the lines of the block) →
  ``tgsis.geometry.crs``.
* ``metadata["color"]`` → ``tgsis.geometry.colorred/green/blue`` (``real``);
  components the columns cannot give back exactly (a fourth one, or more
  digits than a ``real`` keeps) stay in ``metadata``.
* ``metadata["gocad_atoms"]`` (pairs ``[atom, ref]`` of vertex indices) →
  ``tgsis.atom`` rows ``(vrtxid, refid)``.
* the ``part`` cell property, when the class has no ``part`` column →
  ``tgsis.part`` rows: runs of simplex ids with the same part number.
* everything else in ``metadata`` that is JSON → ``tgsis.geometry.metadata``.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis._vertex_metadata import places_of_ids
from tgsis._zpositive import z_convention
from tgsis.errors import InvalidGeometryError
from tgsis.mesh import GeometryCollection, Mesh

__all__ = ["Meaning", "meaning_of", "z_convention", "restore_meaning", "part_runs", "parts_from_runs"]

log = logging.getLogger(__name__)

IntArray = npt.NDArray[np.int64]

#: metadata keys that have columns or tables of their own
_OWN_PLACE = ("zpositive", "gocad_coordinate_system", "gocad_atoms", "gocad_patoms", "color")


def _float32_exact(value: float) -> bool:
    """Whether a ``real`` column gives ``value`` back: its float32 shortest text reads back as the same double."""
    return float(str(np.float32(value))) == float(value)


@dataclass(frozen=True)
class Meaning:
    """What a mesh's file meant, as stored: columns of ``tgsis.geometry`` and rows of ``tgsis.atom``/``part``."""

    zpositive: str | None
    crs: list[str] | None
    color: list[float] | None
    metadata: dict[str, Any] | None
    atoms: list[tuple[int, int]]
    patoms: frozenset[int] = frozenset()

    @property
    def depth(self) -> bool:
        """z is down positive: stored z is its negation."""
        return self.zpositive == "Depth"

    def crs_json(self) -> str | None:
        return None if self.crs is None else json.dumps(self.crs)

    def metadata_json(self) -> str | None:
        return None if self.metadata is None else json.dumps(self.metadata)


def _jsonable(key: str, value: Any) -> bool:
    try:
        json.dumps(value, allow_nan=False)
    except (TypeError, ValueError):
        log.warning("metadata[%r] is not JSON and is not stored", key)
        return False
    return True


def meaning_of(mesh: Mesh | Any, what: str = "the mesh") -> Meaning:
    """The meaning of a mesh's (or a collection's) metadata, checked.

    Atom pairs that are not two vertex indices at the same place (an edit
    moved or renumbered them) are left out, with a warning.

    Raises
    ------
    InvalidGeometryError
        A z convention other than Elevation/Depth.
    """
    meta: Mapping[str, Any] = getattr(mesh, "metadata", {}) or {}
    zpositive = z_convention(meta)
    lines = meta.get("gocad_coordinate_system")
    crs = list(lines) if isinstance(lines, (list, tuple)) and all(isinstance(v, str) for v in lines) else None
    extra = {k: v for k, v in meta.items() if k not in _OWN_PLACE and _jsonable(k, v)}
    color: list[float] | None = None
    raw = meta.get("color")
    if (
        isinstance(raw, (list, tuple))
        and len(raw) >= 3
        and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in raw)
    ):
        rgb = [float(c) for c in raw[:3]]
        if all(math.isfinite(c) and 0.0 <= c <= 1.0 for c in rgb):
            color = rgb
            if len(raw) > 3 or not all(_float32_exact(c) for c in rgb):
                extra["color"] = [float(c) for c in raw]  # what the real columns cannot give back
        elif _jsonable("color", list(raw)):
            extra["color"] = list(raw)
    elif raw is not None and _jsonable("color", raw):
        extra["color"] = raw
    atoms: list[tuple[int, int]] = []
    pairs = meta.get("gocad_atoms")
    vertices = getattr(mesh, "vertices", None)
    if isinstance(pairs, (list, tuple)) and vertices is not None:
        bits = vertices.view(np.int64)
        dropped = 0
        for pair in pairs:
            if (
                isinstance(pair, (list, tuple))
                and len(pair) == 2
                and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in pair)
                and 0 <= int(pair[0]) < len(bits)
                and 0 <= int(pair[1]) < len(bits)
                and int(pair[0]) != int(pair[1])
                and np.array_equal(bits[int(pair[0])], bits[int(pair[1])])
            ):
                atoms.append((int(pair[0]), int(pair[1])))
            else:
                dropped += 1
        if dropped:  # an edit moved or renumbered the vertices: such an atom is a vertex of its own now
            log.warning(
                "%d of the atoms in metadata['gocad_atoms'] of %s no longer repeat a vertex at the same "
                "place and are stored as plain vertices",
                dropped,
                what,
            )
    flagged = meta.get("gocad_patoms")
    patoms = (
        frozenset(int(v) for v in flagged if isinstance(v, (int, np.integer)))
        if isinstance(flagged, (list, tuple))
        else frozenset()
    )
    return Meaning(zpositive, crs, color, extra or None, atoms, patoms & {a for a, _ in atoms})


def part_runs(parts: npt.NDArray[Any]) -> tuple[IntArray, IntArray, IntArray]:
    """Runs of equal part numbers: (first index, last index, part) of each.

    Raises
    ------
    InvalidGeometryError
        Part numbers that are not integers >= 0.
    """
    values = np.asarray(parts)
    if len(values) == 0:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    if values.dtype.kind == "f":
        if not np.all(np.isfinite(values)) or not np.all(values == np.round(values)):
            raise InvalidGeometryError("cell property 'part' must hold whole part numbers >= 0")
    elif values.dtype.kind not in "iub":
        raise InvalidGeometryError(f"cell property 'part' must hold part numbers, not {values.dtype}")
    ints = values.astype(np.int64)
    if ints.min() < 0 or ints.max() > 2**31 - 1:
        raise InvalidGeometryError("cell property 'part' must hold part numbers 0 .. 2147483647")
    starts = np.concatenate([[0], np.flatnonzero(ints[1:] != ints[:-1]) + 1]).astype(np.int64)
    ends = np.concatenate([starts[1:] - 1, [len(ints) - 1]]).astype(np.int64)
    return starts, ends, ints[starts]


def parts_from_runs(cell_ids: IntArray, firsts: IntArray, lasts: IntArray, numbers: IntArray) -> IntArray:
    """The part number of each cell (ids ascending) from stored runs; cells in no run get part -1."""
    result = np.full(len(cell_ids), -1, dtype=np.int64)
    if len(firsts) == 0 or len(cell_ids) == 0:
        return result
    order = np.argsort(firsts)
    firsts, lasts, numbers = firsts[order], lasts[order], numbers[order]
    run = np.searchsorted(firsts, cell_ids, side="right") - 1
    inside = (run >= 0) & (cell_ids <= lasts[np.maximum(run, 0)])
    result[inside] = numbers[run[inside]]
    return result


def restore_meaning(
    mesh: Mesh | GeometryCollection,
    zpositive: str | None,
    crs: Sequence[str] | None,
    color: Sequence[Any] | None,
    metadata: Mapping[str, Any] | None,
    atoms: Sequence[tuple[int, int]] = (),
    patoms: Sequence[int] = (),
    vertex_ids: IntArray | None = None,
) -> None:
    """Give a mesh read from storage back its file's meaning (in place): z convention, metadata, atoms.

    ``mesh.vertices`` are the stored (elevation) ones; for Depth their z is negated. ``vertex_ids`` (n,)
    int64 ascending, the ids of the mesh's vertices: the metadata's vertex flags and control nodes, stored by
    id, become places in the mesh (``tgsis._vertex_metadata.places_of_ids``).
    """
    if zpositive == "Depth" and isinstance(mesh, Mesh):
        mesh.vertices[:, 2] = -mesh.vertices[:, 2]
    meta: dict[str, Any] = dict(metadata or {})
    if vertex_ids is not None and meta:
        meta = places_of_ids(meta, vertex_ids, getattr(mesh, "name", None))
    if crs is not None:
        meta["gocad_coordinate_system"] = list(crs)
    if zpositive is not None:
        written = zpositive
        for line in crs or ():
            words = line.split()
            if len(words) >= 2 and words[0] == "ZPOSITIVE" and words[1].lower() == zpositive.lower():
                written = words[1]  # as the file spelled it
        meta["zpositive"] = written
    columns = [c for c in (color or ()) if c is not None]
    if len(columns) == 3:
        stored = meta.get("color")
        if (
            isinstance(stored, list)
            and len(stored) >= 3
            and all(isinstance(c, (int, float)) for c in stored)
            and [float(np.float32(c)) for c in stored[:3]] == [float(np.float32(c)) for c in columns]
        ):
            meta["color"] = tuple(float(c) for c in stored)  # exact, as the file had it
        else:
            meta["color"] = tuple(float(str(np.float32(c))) for c in columns)  # the columns (maybe edited in SQL)
    if atoms:
        meta["gocad_atoms"] = [[int(a), int(r)] for a, r in atoms]
    if patoms:
        meta["gocad_patoms"] = [int(a) for a in patoms]
    mesh.metadata = {**mesh.metadata, **meta}
