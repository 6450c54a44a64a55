"""New rows of a check-in take ids above every id the object ever had: at the end of bigint, refused by name.

The local id columns (vrtxid, trglid, ...) are bigint. A check-in by
difference gives the rows it adds the ids above the object's largest id, of
every stored version (``tgsis.db.checkin``): where that largest id is near
2**63 - 1 (a psql user may insert any id), the next ids would wrap to
negative numbers in numpy (or fail in the server). The check-in is refused
(TG100, ``InvalidInputError``) before anything is written, on both storages
(the test's storage: PostgreSQL 15 runs chunks, 18 rows); up to the last id
it still works.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.storage_data import stored_versions
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

LARGEST = 2**63 - 1


def _surface() -> tgsis.Surface:
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.5], [0.0, 1.0, 0.25], [1.0, 1.0, 0.125]])
    return tgsis.Surface(vertices, np.array([[0, 1, 3], [0, 3, 2]]), name="top")


def _feature(conn: Conn, versioned: bool) -> int:
    F.create_feature_class(conn, "horizons", "SURFACE")
    if versioned:
        tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "horizons", _surface())
    conn.commit()
    return geoid


def _with_more(mesh: tgsis.Mesh, vertices: int, cells: int) -> tgsis.Surface:
    """``mesh`` with ``vertices`` new vertices and ``cells`` new triangles on its first three vertices."""
    extra = np.arange(vertices, dtype=float)[:, None] + np.array([[5.0, 5.0, 5.0]])
    new_cells = np.array([[0, 2, 1]] * cells, dtype=np.int64).reshape(-1, 3)
    return tgsis.Surface(np.concatenate([mesh.vertices, extra]), np.concatenate([mesh.cells, new_cells]), name="top")


def _storage(conn: Conn) -> dict[str, list[Any]]:
    state = {t: stored_versions(conn, t) for t in ("vrtx", "trgl", "geometry")}
    conn.commit()
    return state


@pytest.mark.parametrize("versioned", [False, True], ids=["unversioned", "versioned"])
def test_new_vertices_past_the_last_bigint_are_refused_by_name(conn: Conn, versioned: bool) -> None:
    geoid = _feature(conn, versioned)
    conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 9, 9, 9)", (geoid, LARGEST))
    conn.commit()
    checked_out = tgsis.checkout(conn, geoid)
    before = _storage(conn)
    with pytest.raises(tgsis.InvalidInputError) as refused:
        tgsis.checkin(conn, checked_out, _with_more(checked_out.mesh, 1, 0))
    conn.rollback()
    assert refused.value.sqlstate == "TG100"
    assert f"feature {geoid}: the edit adds 1 vertex row(s) to tgsis.vrtx" in str(refused.value)
    assert f"({LARGEST})" in str(refused.value) and "nothing was written" in str(refused.value)
    assert (
        refused.value.hint == "store the edited mesh as a new feature (its ids start again from 0) and delete this one"
    )
    assert _storage(conn) == before


def test_a_deleted_row_s_id_still_counts_in_a_versioned_object(conn: Conn) -> None:
    """Ids are never given again in a versioned object: the largest id of every stored version counts."""
    geoid = _feature(conn, True)
    conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 9, 9, 9)", (geoid, LARGEST))
    conn.commit()
    tgsis.save_revision(conn, "with the last id")
    conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (geoid, LARGEST))
    conn.commit()
    checked_out = tgsis.checkout(conn, geoid)
    assert checked_out.mesh.n_vertices == 4
    before = _storage(conn)
    with pytest.raises(tgsis.InvalidInputError, match="adds 2 vertex row"):
        tgsis.checkin(conn, checked_out, _with_more(checked_out.mesh, 2, 0))
    conn.rollback()
    assert _storage(conn) == before


@pytest.mark.parametrize("versioned", [False, True], ids=["unversioned", "versioned"])
def test_new_cells_past_the_last_bigint_are_refused_by_name(conn: Conn, versioned: bool) -> None:
    geoid = _feature(conn, versioned)
    conn.execute(
        "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 1, 2, 3)", (geoid, LARGEST)
    )
    conn.commit()
    checked_out = tgsis.checkout(conn, geoid)
    before = _storage(conn)
    with pytest.raises(tgsis.InvalidInputError, match=r"adds 1 cell row\(s\) to tgsis.trgl"):
        tgsis.checkin(conn, checked_out, _with_more(checked_out.mesh, 0, 1))
    conn.rollback()
    assert _storage(conn) == before


@pytest.mark.parametrize("versioned", [False, True], ids=["unversioned", "versioned"])
def test_new_rows_up_to_the_last_bigint_are_written(conn: Conn, versioned: bool) -> None:
    """Two free ids left: two new vertices and two new triangles take them, the last one included."""
    geoid = _feature(conn, versioned)
    conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 9, 9, 9)", (geoid, LARGEST - 2))
    conn.execute(
        "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 1, 2, 3)",
        (geoid, LARGEST - 2),
    )
    conn.commit()
    checked_out = tgsis.checkout(conn, geoid)
    tgsis.checkin(conn, checked_out, _with_more(checked_out.mesh, 2, 2))
    conn.commit()
    vertices = conn.execute("SELECT vrtxid FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall()
    assert [v for (v,) in vertices] == [0, 1, 2, 3, LARGEST - 2, LARGEST - 1, LARGEST]
    cells = conn.execute("SELECT trglid FROM tgsis.trgl WHERE geoid = %s ORDER BY trglid", (geoid,)).fetchall()
    assert [c for (c,) in cells] == [0, 1, LARGEST - 2, LARGEST - 1, LARGEST]
