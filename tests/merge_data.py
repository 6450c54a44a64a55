"""A curved, versioned fault and moves of its vertices: the set-up of the tests of a merge read from the database."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

import tgsis
from tests.storage_data import in_chunks, stored_versions
from tgsis.db import features as F
from tgsis.db.classes import class_of_feature
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]

SIDE = 12


def curved_surface(side: int = SIDE) -> tgsis.Surface:
    """A side x side grid bent into a curved sheet (z = sin x cos y), coordinates with full mantissas."""
    u, v = np.meshgrid(np.linspace(0.0, 3.1, side), np.linspace(0.0, 2.7, side))
    vertices = np.stack([u.ravel() * 1000.3, v.ravel() * 997.1, 150.0 * np.sin(u.ravel()) * np.cos(v.ravel())], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    cells = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return tgsis.Surface(
        vertices,
        cells,
        vertex_properties={"porosity": np.linspace(0.1, 0.3, side * side)},
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


def every_view(conn: Conn) -> list[tuple[str, int | None]]:
    """(version, revision) of every working set (revision None) and every revision a version can look at."""
    views: list[tuple[str, int | None]] = [
        (r[0], None) for r in conn.execute("SELECT name FROM tgsis.versions ORDER BY versionid").fetchall()
    ]
    views += [
        (r[0], int(r[1]))
        for r in conn.execute(
            "SELECT v.name, r.revision FROM tgsis.versions v JOIN tgsis.revisions r "
            "ON (r.revision = ANY (v.workingset) OR r.versionid = v.versionid) AND r.visibleset IS NOT NULL "
            "ORDER BY 1, 2"
        ).fetchall()
    ]
    return views


def varied_history(conn: Conn, geoid: int) -> None:
    """Rows with real revisions and lastrevs, through the public API only (on top of make_fault: DEFAULT, e1).

    Moves in two versions, saved revisions, a check-in deleting a grid row, an object inserted then
    deleted, two merges, a version deleting the object (the chunk conversion and switch tests).
    """
    move(conn, "e1", geoid, [0, 1, 2, 50], (1.5, -2.25, 0.125))
    tgsis.save_revision(conn, "e1 first")
    conn.commit()
    move(conn, "e1", geoid, [3, 50, 143], (0.0, 0.0, -7.0))
    tgsis.create_version(conn, "e2", "e1")
    conn.commit()
    move(conn, "e2", geoid, [10, 11], (3.0, 3.0, 3.0))
    # a deletion of vertices and triangles: the last row of the grid goes in a check-in by difference
    with tgsis.in_version(conn, "e2"):
        state = F.fetch_feature(conn, "faults", geoid).mesh
        assert isinstance(state, Surface)
        keep = np.arange(state.n_vertices - 12)
        inside = np.all(state.cells < len(keep), axis=1)
        smaller = Surface(
            state.vertices[keep],
            state.cells[inside],
            vertex_properties={k: v[keep] for k, v in state.vertex_properties.items()},
            cell_properties={k: v[inside] for k, v in state.cell_properties.items()},
        )
        tgsis.save_feature(conn, "faults", geoid, smaller)
        conn.commit()
    # another object, inserted then deleted in e1's history
    with tgsis.in_version(conn, "e1"):
        triangle = Surface(
            np.eye(3) * 4.0,
            np.array([[0, 1, 2]]),
            vertex_properties={"porosity": np.array([0.1, 0.2, 0.3])},
            cell_properties={"facies": np.array([2], dtype=np.int32)},
        )
        other = F.insert_feature(conn, "faults", triangle)
        conn.commit()
    tgsis.goto_version(conn, "e1")
    tgsis.save_revision(conn, "with other")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        move(conn, "e1", other, [1], (0.5, 0.5, 0.5))
        assert F.delete_feature(conn, "faults", other)
        conn.commit()
    tgsis.goto_version(conn, "DEFAULT")
    conn.commit()
    # a merge into the parent (e2 -> e1), and e1 -> DEFAULT
    tgsis.merge_version(conn, "e2")
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    move(conn, "e2", geoid, [20], (1.0, 0.0, 0.0))
    # a version that deletes the whole object
    tgsis.create_version(conn, "gone")
    conn.commit()
    with tgsis.in_version(conn, "gone"):
        assert F.delete_feature(conn, "faults", geoid)
        conn.commit()
    move(conn, "DEFAULT", geoid, [30, 31], (0.0, -1.0, 0.0))
    conn.commit()


def sqlstate(conn: Conn, statement: str, params: Any = ()) -> tuple[str | None, str]:
    """The SQLSTATE and message of a statement run in a savepoint (None, "" when it succeeds)."""
    try:
        with conn.transaction():
            conn.execute(statement, params)
    except psycopg.Error as exc:
        return exc.sqlstate, str(exc)
    return None, ""


#: model 1's tables stored in chunks: their local-id column and value columns (the chunk tests compare them)
MODEL1_COLUMNS = {
    "vrtx": ("vrtxid", ["x", "y", "z"]),
    "point": ("pointid", ["vrtxid1"]),
    "segment": ("segid", ["vrtxid1", "vrtxid2"]),
    "trgl": ("trglid", ["vrtxid1", "vrtxid2", "vrtxid3"]),
    "tetra": ("tetraid", ["vrtxid1", "vrtxid2", "vrtxid3", "vrtxid4"]),
}


# --- storage-neutral checks of what a merge writes (issue 40): rows or chunks, named through the product


def merge_storage_state(conn: Conn) -> dict[str, list[Any]]:
    """Every stored version of the model tables vrtx, trgl, geometry (rows or chunk versions, through
    ``tgsis.storage_table``), the versions and the conflicts: what "nothing written" compares (committed)."""
    state = {t: stored_versions(conn, t) for t in ("vrtx", "trgl", "geometry")}
    for catalog in ("versions", "conflicts"):
        state[catalog] = conn.execute(f"SELECT * FROM tgsis.{catalog} ORDER BY 1, 2, 3").fetchall()
    conn.commit()
    return state


def rewrites_same_values(conn: Conn, table: str = "vrtx") -> bool:
    """Whether an ``UPDATE`` of model table ``tgsis.<table>`` writing a row's own values back writes a new version
    of it (the object changed).

    Rows: yes. Chunks: no, a chunk whose content is unchanged bit for bit is not written (docs/storage.md,
    "What differs from rows").
    """
    return not in_chunks(conn, table)


def stored_unit(conn: Conn, schema: str, table: str) -> Callable[[tuple[str, ...]], tuple[str, ...]]:
    """The key of the stored version holding a row, from the row's key (``versioned_tables.keycolumns``, as text).

    Rows: the row key itself. A model or class table stored in chunks: its ``tgsis.storage_key`` (the local id
    replaced by its chunk, id div the chunk size of ``tgsis.chunk_registry``), so that "the rows a merge wrote" reads as "the
    chunk versions holding them" (docs/storage.md, "What differs from rows").
    """
    row = conn.execute(
        "SELECT v.keycolumns, tgsis.storage_key(v), (SELECT r.chunksize FROM tgsis.chunk_registry("
        "           CASE WHEN v.schemaname = 'tgsis' THEN v.tablename ELSE format('%%I.%%I', v.schemaname, v.tablename) END) r)"
        "  FROM tgsis.versioned_tables v WHERE v.schemaname = %s AND v.tablename = %s",
        (schema, table),
    ).fetchone()
    assert row is not None, f"{schema}.{table} is not versioned"
    keys, stored, size = list(row[0]), list(row[1]), row[2]
    if keys == stored:
        return lambda key: key
    at = stored.index("chunk")
    return lambda key: tuple(str(int(k) // int(size)) if i == at else k for i, k in enumerate(key))
