"""Merges on chunks sized by the change: only the slots that differ count as changed keys (issue 40).

A chunk version carries all its slots, so a merge that took every slot of a
changed chunk for a changed key worked on 1,024 keys for one moved vertex (the
regions' work tables of ``tgsis.mesh_merge_work``, ``tgsis.conflict_discards``,
the merged mesh's validity, the Python merge's change and its ring).
``tgsis.storage_changed_rows`` compares the chunk versions the base, the parent
and the child see slot by slot, bit for bit. Each scenario is run on rows and
on chunks (the edits made through the face after the switch): the work holds
exactly the changed ids on chunks, and the regions, the discards, the Python
merge's regions and the mesh the SQL merge writes are those of the rows. The
scenarios hold edits that are not changes there: a value written again with
its own bits (left out), -0.0 over 0.0 and NaN payloads (bit for bit a change,
for merge3 not a move: the outcome is the rows').
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterator
from typing import Any

import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, move
from tests.test_sql_merge_regions import python_regions, sql_regions
from tgsis.db import features as F
from tgsis.db._merge_states import read_merge_change
from tgsis.merge3 import three_way_merge
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]

SIDE = 40  # 1,600 vertices (chunks 0 and 1), 3,042 triangles (chunks 0 to 2)
CHUNKED = (
    "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables WHERE chunkdefault"
    " AND NOT tgsis.stored_in_chunks(tablename) ORDER BY model, iudorder, tablename"
)
MIDDLE = [10 * SIDE + 10, 10 * SIDE + 11, 11 * SIDE + 10]
EAST = [1024 + 7, 1024 + 8, 1100]
NAN_A = struct.unpack(">d", bytes.fromhex("7ff8000000000001"))[0]
NAN_B = struct.unpack(">d", bytes.fromhex("7ff8000000000002"))[0]


@pytest.fixture(scope="module")
def rows_fault(pg: TestServer) -> Iterator[tuple[str, int]]:
    """(database, geoid): tgsis on rows, the curved grid in class faults of DEFAULT, version e1 based on it."""
    with pg.database("tgsis_g_slots") as (name, dsn):
        with psycopg.connect(dsn) as conn:
            tgsis.install(conn, method="extension" if pg.extension_files is None else "sql", storage="rows")
            conn.commit()
            F.create_feature_class(
                conn,
                "faults",
                "SURFACE",
                cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
            )
            tgsis.enable_feature_versioning(conn)
            geoid = F.insert_feature(conn, "faults", curved_surface(SIDE))
            tgsis.create_version(conn, "e1")
            conn.commit()
        yield name, geoid


def _sql(conn: Conn, version: str, statement: str, params: tuple[Any, ...]) -> None:
    with tgsis.in_version(conn, version):
        conn.execute(statement, params)
    conn.commit()


def same_bits(conn: Conn, geoid: int) -> None:
    """The child writes vertices of chunk 1 and triangles of chunk 2 again with their own values, and moves the
    middle; the parent moves the middle and vertices of chunk 1."""
    _sql(conn, "e1", "UPDATE tgsis.vrtx SET x = x, z = z WHERE geoid = %s AND vrtxid BETWEEN 1200 AND 1260", (geoid,))
    _sql(
        conn,
        "e1",
        "UPDATE tgsis.trgl SET vrtxid1 = vrtxid1 WHERE geoid = %s AND trglid BETWEEN 2100 AND 2150",
        (geoid,),
    )
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    move(conn, "DEFAULT", geoid, EAST, (-0.125, 0.0, 0.0))
    conn.commit()


def signed_zero(conn: Conn, geoid: int) -> None:
    """The child writes -0.0 over vertex 0's x (0.0) and moves the middle; the parent moves the middle."""
    _sql(conn, "e1", "UPDATE tgsis.vrtx SET x = '-0'::float8 WHERE geoid = %s AND vrtxid = 0", (geoid,))
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()


def nan_payloads(conn: Conn, geoid: int) -> None:
    """Both sides write NaN into vertex 5's z, with different payloads (sent in binary: the bits arrive), and move the
    middle differently."""
    for version, nan in (("e1", NAN_A), ("DEFAULT", NAN_B)):
        _sql(conn, version, "UPDATE tgsis.vrtx SET z = %b WHERE geoid = %s AND vrtxid = 5", (nan, geoid))
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()


def cells(conn: Conn, geoid: int) -> None:
    """The child reconnects triangle 900 (two corners swapped); the parent moves one of its corners and writes
    triangles of chunk 2 again with their own values."""
    _sql(
        conn,
        "e1",
        "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = 900",
        (geoid,),
    )
    corner = conn.execute("SELECT vrtxid3 FROM tgsis.trgl WHERE geoid = %s AND trglid = 900", (geoid,)).fetchone()
    conn.rollback()
    assert corner is not None
    move(conn, "DEFAULT", geoid, [int(corner[0])], (0.5, 0.5, 0.5))
    _sql(conn, "DEFAULT", "UPDATE tgsis.trgl SET vrtxid3 = vrtxid3 WHERE geoid = %s AND trglid >= 2048", (geoid,))
    conn.commit()


def hole(conn: Conn, geoid: int) -> None:
    """The child deletes triangle 901 (a hole in its chunk); the parent moves one of its corners."""
    _sql(conn, "e1", "DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 901", (geoid,))
    move(conn, "DEFAULT", geoid, [965], (0.5, -0.5, 0.25))
    conn.commit()


# scenario: (edits, the changed vertex ids, the changed cell ids, whether rows count more keys (same values again))
SCENARIOS: dict[str, tuple[Callable[[Conn, int], None], set[int], set[int], bool]] = {
    "same_bits": (same_bits, {*MIDDLE, *EAST}, set(), True),
    "signed_zero": (signed_zero, {0, *MIDDLE}, set(), False),
    "nan_payloads": (nan_payloads, {5, *MIDDLE}, set(), False),
    "cells": (cells, {964}, {900}, True),  # (triangle 900 is (923, 924, 964))
    "hole": (hole, {965}, {901}, False),  # (triangle 901 is (924, 925, 965))
}


def work_keys(conn: Conn, geoid: int) -> tuple[set[int], set[int]]:
    """The vertex and cell ids in the regions' work tables of tgsis.mesh_merge_work (rolled back)."""
    conn.execute("SELECT tgsis.mesh_merge_work('e1', %s)", (geoid,))
    v = {int(r[0]) for r in conn.execute("SELECT DISTINCT id FROM pg_temp.tgsis_mr_v").fetchall()}
    c = {int(r[0]) for r in conn.execute("SELECT DISTINCT id FROM pg_temp.tgsis_mr_c").fetchall()}
    conn.rollback()
    return v, c


def state_bits(conn: Conn, version: str, geoid: int) -> tuple[list[tuple[Any, ...]], list[tuple[Any, ...]]]:
    """The version's vertices (coordinates by their send forms: bit for bit) and triangles."""
    with tgsis.in_version(conn, version):
        vertices = conn.execute(
            "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1",
            (geoid,),
        ).fetchall()
        triangles = conn.execute(
            "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s ORDER BY 1", (geoid,)
        ).fetchall()
    conn.rollback()
    return [(int(r[0]), *(bytes(b) for b in r[1:])) for r in vertices], [tuple(int(c) for c in r) for r in triangles]


def canon(value: Any) -> Any:
    """``value`` with every float as its hex text (NaN equals NaN here: a NaN box or displacement compares)."""
    if isinstance(value, float):
        return value.hex()
    if isinstance(value, dict):
        return {k: canon(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(canon(v) for v in value)
    return value


def attempt(conn: Conn, step: Callable[[], Any]) -> Any:
    """``step()``, or (refused, the error's class and first line) when it raises (rolled back): a refusal is an
    answer to compare too (merge3 refuses non-finite coordinates)."""
    try:
        return step()
    except (psycopg.Error, tgsis.errors.Error) as exc:
        conn.rollback()
        return ("refused", type(exc).__name__, str(exc).split("\n")[0])


def outcome(conn: Conn, geoid: int) -> dict[str, Any]:
    """What the merges make of the scenario: regions (SQL, and merge3's from the whole states), discards, the Python
    merge's regions from the change it reads, and the SQL merge by region (every conflicting region solved child)
    with both states after it."""
    out: dict[str, Any] = {"regions": sql_regions(conn, "e1", geoid)}
    out["merge3"] = attempt(conn, lambda: python_regions(conn, "e1", geoid))
    out["discards"] = conn.execute("SELECT * FROM tgsis.conflict_discards('e1') ORDER BY 1, 2, 3, 4, 5, 6").fetchall()
    conn.rollback()

    def python() -> tuple[set[int], list[tuple[Any, ...]]]:
        change = read_merge_change(conn, "e1", geoid)
        conn.rollback()
        assert change is not None
        inputs, top = change
        merged = three_way_merge(inputs.states["base"], inputs.states["parent"], inputs.states["child"], top_ids=top)
        regions = [(r.index, r.conflict, r.sides, r.vertex_ids.tolist(), r.cell_ids.tolist()) for r in merged.regions]
        return {int(i) for i in inputs.states["base"].vertex_ids}, regions

    out["python"] = attempt(conn, python)
    out["read"] = out["python"][0] if isinstance(out["python"][0], set) else None
    out["python"] = out["python"][1] if isinstance(out["python"][0], set) else out["python"]

    def merge() -> Any:
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
        conn.execute(
            "SELECT tgsis.resolve_region('e1', 'feature', %s, region, 'child') FROM tgsis.conflict_regions"
            " WHERE versionid = tgsis.version_id('e1') AND conflict ORDER BY region",
            (str(geoid),),
        )
        conn.commit()
        conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        written = conn.execute("SELECT tgsis.merge_mesh_by_region('e1', 'merge', %s)", (geoid,)).fetchone()
        conn.commit()
        return written

    out["merge"] = (attempt(conn, merge), state_bits(conn, "e1", geoid), state_bits(conn, "DEFAULT", geoid))
    return out


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_merges_on_chunks_count_changed_slots(
    pg: TestServer, rows_fault: tuple[str, int], make_database: Callable[..., str], scenario: str
) -> None:
    """On chunks the work holds the changed ids only (failed before: every slot of the changed chunks, 1,024 per
    vertex chunk), and every answer of the merges is the rows' one."""
    name, geoid = rows_fault
    edits, vertex_ids, cell_ids, rows_count_more = SCENARIOS[scenario]
    answers = []
    for chunks in (False, True):
        with psycopg.connect(make_database(name)) as conn:
            if chunks:
                conn.execute(CHUNKED)
                conn.commit()
                assert conn.execute(
                    "SELECT tgsis.stored_in_chunks('vrtx') AND tgsis.stored_in_chunks('trgl')"
                ).fetchone() == (True,)
            edits(conn, geoid)
            v, c = work_keys(conn, geoid)
            if chunks:
                assert (v, c) == (vertex_ids, cell_ids)
                # the edits were written as chunk versions of every chunk they touched (the test compares slots)
                written = conn.execute(
                    "SELECT count(DISTINCT chunk) FROM tgsis.vrtx_chunk WHERE geoid = %s AND revision <> 0", (geoid,)
                ).fetchone()
                conn.rollback()
                assert written is not None and written[0] >= 1
            elif rows_count_more:
                assert v >= vertex_ids and c >= cell_ids and (v, c) != (vertex_ids, cell_ids)
            else:
                assert (v, c) == (vertex_ids, cell_ids)
            answers.append(outcome(conn, geoid))
    rows, chunked = answers
    read_rows, read_chunks = rows.pop("read"), chunked.pop("read")
    if read_rows is None:  # (refused alike: merge3 takes no NaN coordinates)
        assert read_chunks is None and scenario == "nan_payloads"
    else:  # the Python merge's change and its ring, not the chunks
        assert read_chunks <= read_rows and (read_chunks == read_rows) != rows_count_more
        assert len(read_chunks) < 200
    assert canon(chunked) == canon(rows)


def test_payloads_arrive(rows_fault: tuple[str, int], make_database: Callable[..., str]) -> None:
    """The NaN payloads and -0.0 of the scenarios reach the chunks bit for bit (else the scenarios test nothing)."""
    name, geoid = rows_fault
    with psycopg.connect(make_database(name)) as conn:
        conn.execute(CHUNKED)
        conn.commit()
        nan_payloads(conn, geoid)
        signed_zero(conn, geoid)
        bits = {}
        for version in ("e1", "DEFAULT"):
            vertices, _ = state_bits(conn, version, geoid)
            bits[version] = {r[0]: r[1:] for r in vertices}
    assert bits["e1"][5][2] == bytes.fromhex("7ff8000000000001")
    assert bits["DEFAULT"][5][2] == bytes.fromhex("7ff8000000000002")
    assert bits["e1"][0][0] == bytes.fromhex("8000000000000000")
    assert bits["DEFAULT"][0][0] == bytes(8)


def test_a_role_with_fewer_rights(rows_fault: tuple[str, int], make_database: Callable[..., str]) -> None:
    """An editor of the version reads the changed slots as the owner does (the function is granted to tgsis's
    roles); a role that may not read the class is refused by the work (42501), not given fewer keys."""
    from tests.roles import login_roles

    name, geoid = rows_fault
    dsn = make_database(name)
    with psycopg.connect(dsn) as conn:
        conn.execute(CHUNKED)
        conn.commit()
        same_bits(conn, geoid)
        owners = work_keys(conn, geoid)
        discards = conn.execute("SELECT * FROM tgsis.conflict_discards('e1') ORDER BY 1, 2, 3, 4, 5, 6").fetchall()
        conn.rollback()
        with login_roles(dsn, {"ed": "tgsis_editor"}) as made:
            tgsis.grant_version(conn, "e1", "write", made.name("ed"))
            conn.commit()
            with made.connect("ed") as ed:
                assert work_keys(ed, geoid) == owners == ({*MIDDLE, *EAST}, set())
                assert (
                    ed.execute("SELECT * FROM tgsis.conflict_discards('e1') ORDER BY 1, 2, 3, 4, 5, 6").fetchall()
                    == discards
                )
                ed.rollback()
                conn.execute("REVOKE SELECT ON public.faults FROM tgsis_editor, tgsis_reader")
                conn.commit()
                with pytest.raises(psycopg.errors.InsufficientPrivilege):
                    work_keys(ed, geoid)
                ed.rollback()
