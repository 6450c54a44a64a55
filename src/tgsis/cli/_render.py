"""Rendering shared by the command modules: how classes are named in messages, pictures of features."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from tgsis.cli._output import out
from tgsis.db.features import FeatureClass, class_of_feature, fetch_feature
from tgsis.db.temporal import get_at, instants, lifespan
from tgsis.db.versions import Difference
from tgsis.errors import InvalidInputError, NotFoundError
from tgsis.mesh import Surface


def time_unit_suffix(fc: FeatureClass) -> str:
    """`` Ma``: the class's unit of model time for messages (empty when it records none)."""
    return f" {fc.time_unit}" if fc.time_unit else ""


def time_model_suffix(fc: FeatureClass) -> str:
    """``, EVOLVING in Ma``-like suffix naming the time model of a temporal class ('' for static ones)."""
    if fc.time_model == "STATIC":
        return ""
    return f", {fc.time_model}" + (f" in{time_unit_suffix(fc)}" if fc.time_unit else "")


def picture_of(conn: Any, ids: Sequence[int], t: float | None, path: str, title: str) -> None:
    """A PNG of features (at t, or static) in one scene; the first coloured by how far it moved since its start."""
    from tgsis import pictures

    shapes = [
        get_at(conn, fid, t) if t is not None else fetch_feature(conn, class_of_feature(conn, fid), fid).mesh
        for fid in ids
    ]
    others = [fid for fid, mesh in zip(ids, shapes) if mesh is not None and not isinstance(mesh, Surface)]
    if others:
        raise InvalidInputError(f"feature {others[0]} is no surface: --png draws surfaces")
    meshes = [mesh for mesh in shapes if isinstance(mesh, Surface)]
    if not meshes:
        raise NotFoundError("none of the features exists then: nothing to draw")
    colour: list[Any] = [None] * len(meshes)
    span = lifespan(conn, ids[0]) if t is not None else None
    first = shapes[0]
    if span is not None and t is not None and isinstance(first, Surface):
        # coloured by displacement only within the first topology period: later ones have other vertices
        changes = [s for s, starts in instants(conn, ids[0]) if starts and span[0] < s <= t]
        start = get_at(conn, ids[0], span[0])
        if not changes and start is not None and start.vertices.shape == first.vertices.shape:
            colour[0] = pictures.displacement(first, start)
    pictures.scene(
        meshes,
        path,
        title=title,
        colour=colour,
        colour_label=f"moved since t = {span[0]!r} (m)" if span is not None else "",
    )
    out(f"drew {len(meshes)} surface(s) to {path}")


@dataclass
class ObjectDifference:
    """What differs of one object between two versions: ``difference`` is ``only in A``, ``only in B`` or
    ``changed``; the rows added, removed and changed summed over its ``tables``."""

    objectclass: str
    objectkey: str
    difference: str
    tables: list[str]
    added: int
    removed: int
    changed: int


def summarize_differences(differences: Sequence[Difference], a: str, b: str) -> list[ObjectDifference]:
    """One :class:`ObjectDifference` per object of ``differences`` (rows per object and table, A to B).

    An object is only in A when every row of it that differs is gone in B and
    none was added or changed (its rows all removed: deleted in B, or added in
    A after B was based); only in B the other way round. A feature is only on
    one side when its ``geometry`` row is, so that a feature that merely lost
    some rows (vertices of a property table) counts as changed.
    """
    grouped: dict[tuple[str, str], list[Difference]] = {}
    for d in differences:
        grouped.setdefault((d.objectclass, d.objectkey), []).append(d)
    result = []
    for (objectclass, objectkey), rows in grouped.items():
        added, removed, changed = (sum(getattr(d, n) for d in rows) for n in ("added", "removed", "changed"))
        tables = [d.table for d in rows]
        whole = objectclass != "feature" or "geometry" in tables
        if whole and changed == 0 and added == 0 and removed > 0:
            what = f"only in {a}"
        elif whole and changed == 0 and removed == 0 and added > 0:
            what = f"only in {b}"
        else:
            what = "changed"
        result.append(ObjectDifference(objectclass, objectkey, what, tables, added, removed, changed))
    return result
