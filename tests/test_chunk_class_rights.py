"""Per-class rights on the G-map readers that read chunk tables as the caller (issue 40, plan O, B2).

``tgsis.md_vertices_in_box`` (model 5's points) and ``tgsis.gmap_conditions_hold`` / ``gmap_conditions``
(through ``tgsis.gmap_chunk_arrays_sql``) read ``tgsis.md_vertex_chunk`` and the darts' and involutions'
chunk tables directly, as the caller, under the chunk tables' row-level security (the class rights
policies copied from the rows by ``tgsis.copy_relation_rights``), where on rows they read the faces or
the rows under the same policies. A role whose class is revoked (tests/test_class_rights.py's pattern)
must get from them what it gets on rows: none of that class's points, none of its map's problems,
while the class it may read answers as to tgsis's owner.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import psycopg
import pytest

from tests.roles import Roles, login_roles
from tests.storage_data import switch_tables, tables_as_rows
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G

from .gmaps_shapes import block_tetrahedra

Conn = psycopg.Connection[Any]

TABLES = ("md_vertex", "gmap_dart", "gmap_alpha", "md_dart", "md_alpha")
MODEL5 = ("tgsis.md_dart", "tgsis.md_alpha", "vrtxid", None)
# a break of the map (tests/test_gmap_check_chunks.py's "non-involution"), made by tgsis's owner
BREAK = "UPDATE tgsis.md_alpha SET dartid2 = dartid2 + 1 WHERE geoid = %s AND level = 0 AND dartid = 8"


class World:
    def __init__(self, roles: Roles, su: Conn, alpha: int, beta: int) -> None:
        self.roles, self.su, self.alpha, self.beta = roles, su, alpha, beta


@pytest.fixture(params=["rows", "chunks"])
def world(request: pytest.FixtureRequest, db_dsn: str, conn: Conn) -> Iterator[World]:
    """alpha and beta, one model-5 map each (alpha's broken, beta's valid), beta's rights revoked from
    tgsis_reader; the G-map tables in the storage of the parameter."""
    tables_as_rows(conn, TABLES)
    solid = gmaps.GMap.from_tetrahedra(*block_tetrahedra(2))
    points = np.column_stack([solid.points, np.arange(solid.n_points) % 3])
    ids = []
    for name in ("alpha", "beta"):
        fc = F.create_feature_class(conn, name, "GMAP", time_model="MULTIDIM", cell_level=3)
        ids.append(G.insert_gmap(conn, fc, gmaps.GMap(solid.alpha, solid.vertex, points), axes=["x", "y", "z", "k"]))
    conn.execute(BREAK, (ids[0],))
    conn.commit()
    if request.param == "chunks":
        switch_tables(conn, TABLES, "chunks")
    for (table,) in conn.execute("SELECT tablename FROM tgsis.class_tables WHERE classname = 'beta'").fetchall():
        conn.execute(f"REVOKE ALL ON {table} FROM tgsis_reader, tgsis_editor, tgsis_admin, PUBLIC")
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        yield World(roles, conn, ids[0], ids[1])


def _points(conn: Conn, geoid: int) -> list[Any]:
    return conn.execute(
        "SELECT * FROM tgsis.md_vertices_in_box(%s, '{k}', '{0.5}', '{1.5}') ORDER BY 1", (geoid,)
    ).fetchall()


def _numbering(su: Conn, geoid: int) -> tuple[Any, ...]:
    """The darts' first and last id and count, as tgsis's owner reads them (what gmap_conditions reads first)."""
    row = su.execute(
        "SELECT min(dartid), max(dartid), count(*) FROM tgsis.md_dart WHERE geoid = %s", (geoid,)
    ).fetchone()
    assert row is not None
    return tuple(row)


def _problems(conn: Conn, geoid: int, numbering: tuple[Any, ...]) -> tuple[Any, list[Any]]:
    """What the one-statement proof says given the map's numbering (a caller may know it), and gmap_conditions."""
    holds = conn.execute(
        "SELECT tgsis.gmap_conditions_hold(%s, 3, %s, %s, %s, %s, %s, %s, %s, false)", (geoid, *MODEL5, *numbering)
    ).fetchone()
    problems = conn.execute(
        "SELECT problem, count, darts FROM tgsis.gmap_conditions(%s, 3, %s, %s, %s, %s)", (geoid, *MODEL5)
    ).fetchall()
    return holds, problems


def _chunk_path(conn: Conn) -> bool:
    row = conn.execute("SELECT arrays IS NOT NULL FROM tgsis.gmap_chunk_arrays_sql(%s, %s, %s, %s)", MODEL5).fetchone()
    return row is not None and bool(row[0])


def test_md_vertices_in_box_gives_no_point_of_a_revoked_class(world: World) -> None:
    reader = world.roles.connect("reader")
    owner_beta = _points(world.su, world.beta)
    assert owner_beta, "the box holds points of beta"
    assert _points(reader, world.alpha) == _points(world.su, world.alpha) == owner_beta
    # as on rows: beta's map is not one the reader sees (tgsis.md_gmap's rights filter), TG200
    with pytest.raises(psycopg.Error) as caught:
        _points(reader, world.beta)
    assert caught.value.sqlstate == "TG200"


def test_the_g_map_checks_report_nothing_of_a_revoked_class(world: World, request: pytest.FixtureRequest) -> None:
    reader = world.roles.connect("reader")
    assert _chunk_path(reader) is (request.node.callspec.params["world"] == "chunks")
    alpha, beta = _numbering(world.su, world.alpha), _numbering(world.su, world.beta)
    broken = _problems(world.su, world.alpha, alpha)
    assert broken[0] == (False,) and broken[1], "the break is seen by tgsis's owner"
    assert _problems(reader, world.alpha, alpha) == broken
    assert _problems(world.su, world.beta, beta) == ((True,), [])
    # beta's darts read by the reader: none (on chunks: the chunk tables' row-level security), so nothing is
    # proved of the map even given its numbering, as on rows; a read of beta's chunks would prove it valid
    assert _problems(reader, world.beta, beta) == ((False,), [])


def test_the_chunk_rows_views_read_with_the_caller_s_rights(world: World, request: pytest.FixtureRequest) -> None:
    """``tgsis.<table>_chunk_rows`` is security_invoker: the chunk table's row-level security (the class
    rights) and a REVOKE on the chunk table by hand reach a role reading through it."""
    if request.node.callspec.params["world"] != "chunks":
        pytest.skip("the chunk rows views exist with the tables in chunks")
    reader = world.roles.connect("reader")
    count = "SELECT count(*) FROM tgsis.md_vertex_chunk_rows WHERE geoid = %s"
    owner = [world.su.execute(count, (g,)).fetchone() for g in (world.alpha, world.beta)]
    assert owner[0] == owner[1] and owner[0] != (0,)
    assert [reader.execute(count, (g,)).fetchone() for g in (world.alpha, world.beta)] == [owner[0], (0,)]
    reader.rollback()
    world.su.execute("REVOKE SELECT ON tgsis.md_vertex_chunk FROM tgsis_reader")
    world.su.commit()
    with pytest.raises(psycopg.errors.InsufficientPrivilege):
        reader.execute(count, (world.alpha,))
    reader.rollback()
    # the readers that read the chunk table as the caller take the face then (tgsis.md_vertices_in_box)
    assert _points(reader, world.alpha) == _points(world.su, world.alpha)
