"""A curved, versioned fault and moves of its vertices: the set-up of the tests of a merge read from the database."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

import tgsis
from tgsis.db import features as F
from tgsis.db.classes import class_of_feature

Conn = psycopg.Connection[Any]

SIDE = 12


def curved_surface() -> tgsis.Surface:
    """A SIDE x SIDE grid bent into a curved sheet (z = sin x cos y), coordinates with full mantissas."""
    u, v = np.meshgrid(np.linspace(0.0, 3.1, SIDE), np.linspace(0.0, 2.7, SIDE))
    vertices = np.stack([u.ravel() * 1000.3, v.ravel() * 997.1, 150.0 * np.sin(u.ravel()) * np.cos(v.ravel())], axis=1)
    idx = np.arange(SIDE * SIDE).reshape(SIDE, SIDE)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    cells = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return tgsis.Surface(
        vertices,
        cells,
        vertex_properties={"porosity": np.linspace(0.1, 0.3, SIDE * SIDE)},
        cell_properties={"facies": np.arange(len(cells), dtype=np.int32) % 5},
        name="fault",
    )


def make_fault(conn: Conn, metadata: dict[str, Any] | None = None) -> int:
    """One curved surface (``metadata`` added) in class faults of DEFAULT, and version e1 based on it (committed)."""
    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    surface.metadata.update(metadata or {})
    geoid = F.insert_feature(conn, "faults", surface)
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def move(conn: Conn, version: str, geoid: int, ids: npt.ArrayLike, shift: tuple[float, float, float]) -> None:
    """Move vertices ``ids`` by ``shift`` in ``version`` (one committed UPDATE, as a psql user would)."""
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.vrtx SET x = x + %s, y = y + %s, z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)",
            (*shift, geoid, [int(i) for i in np.asarray(ids)]),
        )


def stored_state(conn: Conn, version: str, geoid: int) -> tuple[Any, Any, set[tuple[int, ...]], Any]:
    """(vertex ids, (n, 3) coordinates, cells as a set of (id, v1, v2, v3), porosity) as a psql user reads them.

    Read through the versioned views after ``tgsis.goto_version`` (the session is put back by ``in_version``).
    """
    with tgsis.in_version(conn, version):
        vertices = conn.execute(
            "SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)
        ).fetchall()
        cells = conn.execute("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s", (geoid,))
        cell_set = {tuple(int(v) for v in row) for row in cells.fetchall()}
        fc = class_of_feature(conn, geoid)
        porosity = conn.execute(
            sql.SQL("SELECT _idx, porosity FROM {} WHERE _geoid = %s ORDER BY _idx").format(
                fc.qualified(fc.property_table("VERTEX") or "")
            ),
            (geoid,),
        ).fetchall()
    ids = np.array([r[0] for r in vertices], dtype=np.int64)
    xyz = np.array([r[1:] for r in vertices], dtype=np.float64).reshape(-1, 3)
    return ids, xyz, cell_set, dict(porosity)


def moved(vertices: npt.NDArray[np.float64], ids: npt.ArrayLike, shift: tuple[float, float, float]) -> None:
    """The same move made in Python (float8 + float8 in PostgreSQL and numpy are both IEEE: bit for bit)."""
    at = np.asarray(ids)
    for axis in range(3):
        vertices[at, axis] = vertices[at, axis] + shift[axis]


def with_duplicated_triangle(state: Any) -> Any:
    """``state`` (a MeshState) with a second triangle on the nodes of its first, rotated (merge3 refuses it as
    "duplicated triangles"), a new id past the largest and the first triangle's property values."""
    import dataclasses

    return dataclasses.replace(
        state,
        cell_ids=np.append(state.cell_ids, int(state.cell_ids.max()) + 1000),
        cells=np.vstack([state.cells, state.cells[:1, [1, 2, 0]]]),
        cell_properties={k: np.append(v, np.asarray(v)[:1]) for k, v in state.cell_properties.items()},
    )
