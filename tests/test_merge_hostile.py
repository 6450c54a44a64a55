"""Hostile cases of the merges that write by region and of the region store (issue 39 review)."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import curved_surface, move, moved, stored_state
from tests.roles import login_roles
from tgsis.db import features as F
from tgsis.db.classes import class_of_feature
from tgsis.db.regions import state_to_npz
from tgsis.merge3 import MeshState, apply_solutions

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's, built once (tests/conftest.py)


def _overlapping_edits(conn: Conn, fault: int) -> tgsis.ConflictRegion:
    """One conflicting region (vertex 66 moved differently on both sides), recorded; returned."""
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    (conflict,) = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    (region,) = [r for r in conflict.regions if r.conflict]
    return region


def test_an_average_solution_is_named_average_in_what_it_discards(
    conn: Conn, fault: int, caplog: pytest.LogCaptureFixture
) -> None:
    region = _overlapping_edits(conn, fault)
    resolution = tgsis.resolve_region(conn, "e1", fault, region.region, "average")
    conn.commit()
    assert resolution.discards and {d.solution for d in resolution.discards} == {"average"}
    assert "manual" not in resolution.summary() and "average discards" in resolution.summary()
    with caplog.at_level(logging.WARNING, logger="tgsis.db.merging"):
        result = tgsis.merge_version(conn, "e1")
    (merged,) = result.objects
    assert merged.discards and {d.solution for d in merged.discards} == {"average"}
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert warnings and all("solved average" in w for w in warnings), warnings


NORTH = np.arange(0, 24)  # the first two rows of the grid
SOUTH = np.arange(120, 144)  # the last two


def _fault_with_status(conn: Conn) -> int:
    """The curved fault (porosity per vertex) in class 'faults' with a feature attribute 'status' = 'a'; version e1."""
    F.create_feature_class(
        conn, "faults", "SURFACE", feature_properties=[("status", "text")], cell_properties=[("porosity", "float8")]
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    plain = tgsis.Surface(surface.vertices, surface.cells, vertex_properties=dict(surface.vertex_properties))
    geoid = F.insert_feature(conn, "faults", plain, {"status": "a"})
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def _looks(conn: Conn, version: str, geoid: int) -> tuple[Any, ...]:
    with tgsis.in_version(conn, version):
        row = conn.execute(
            "SELECT g.geoname, g.colorred, g.metadata, f.status FROM tgsis.geometry g JOIN faults f ON f._geoid = g.geoid"
            " WHERE g.geoid = %s",
            (geoid,),
        ).fetchone()
    conn.commit()
    assert row is not None
    return tuple(row)


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_the_parents_edit_of_the_objects_attributes_is_kept_by_a_merge_by_region(conn: Conn, action: str) -> None:
    # was: the merged mesh went into the version and was recorded manual, so the version's geometry and
    # feature rows (the base's) replaced the parent's new name, colour, metadata and status: lost, silently
    geoid = _fault_with_status(conn)
    move(conn, "e1", geoid, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -2.0))
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute(
            "UPDATE tgsis.geometry SET geoname = 'renamed', colorred = 0.5, metadata = '{\"by\": \"parent\"}' "
            "WHERE geoid = %s",
            (geoid,),
        )
        conn.execute("UPDATE faults SET status = 'checked' WHERE _geoid = %s", (geoid,))
    conn.commit()
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, (0.0, 0.0, 3.0))
    moved(expected, SOUTH, (0.0, 0.0, -2.0))
    result = tgsis.merge_version(conn, "e1") if action == "merge" else tgsis.refresh_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    if action == "refresh":  # then a merge: the version's rows must not take the parent's edits back
        assert _looks(conn, "e1", geoid) == ("renamed", 0.5, {"by": "parent"}, "checked")
        assert stored_state(conn, "e1", geoid)[1].tobytes() == expected.tobytes()
        tgsis.merge_version(conn, "e1")
    for version in ("DEFAULT", "e1"):
        assert _looks(conn, version, geoid) == ("renamed", 0.5, {"by": "parent"}, "checked"), version
        assert stored_state(conn, version, geoid)[1].tobytes() == expected.tobytes()


def test_the_versions_edit_of_the_objects_attributes_is_kept_too(conn: Conn) -> None:
    geoid = _fault_with_status(conn)
    move(conn, "e1", geoid, NORTH, (0.0, 0.0, 3.0))
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE tgsis.geometry SET geoname = 'mine' WHERE geoid = %s", (geoid,))
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -2.0))
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE faults SET status = 'checked' WHERE _geoid = %s", (geoid,))
    conn.commit()
    tgsis.merge_version(conn, "e1")
    assert _looks(conn, "DEFAULT", geoid) == ("mine", None, None, "checked")


def test_a_name_changed_on_both_sides_to_other_values_is_not_merged_by_region(conn: Conn) -> None:
    geoid = _fault_with_status(conn)
    for version, name, ids in (("e1", "mine", NORTH), ("DEFAULT", "theirs", SOUTH)):
        move(conn, version, geoid, ids, (0.0, 0.0, 1.0))
        with tgsis.in_version(conn, version):
            conn.execute("UPDATE tgsis.geometry SET geoname = %s WHERE geoid = %s", (name, geoid))
        conn.commit()
    with pytest.raises(tgsis.UnsolvedConflictsError, match=rf"feature {geoid}: .*geoname"):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    assert _looks(conn, "DEFAULT", geoid)[0] == "theirs" and _looks(conn, "e1", geoid)[0] == "mine"


def test_a_role_that_may_not_change_the_class_cannot_record_a_mesh_the_merge_would_write(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    # was: tgsis.resolve_region (SECURITY DEFINER) took any role's manual mesh with the write right on the
    # version only; the merge of a role that may change the class then wrote those coordinates into the
    # version and the parent, for a role that may not change the class
    region = _overlapping_edits(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.commit()
    state = apply_solutions(merge, {region.region: "child"}).state
    at = np.searchsorted(state.vertex_ids, region.vertex_ids)
    xyz = state.vertices.copy()
    xyz[at, 2] += 1000.0
    forged = MeshState(
        3, state.vertex_ids, xyz, state.cell_ids, state.cells, state.vertex_properties, state.cell_properties, "forged"
    )
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "write", made.name("ed"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.faults FROM tgsis_editor")
        conn.commit()
        ed = made.connect("ed")
        for solution in ("manual", "average"):
            with pytest.raises(psycopg.errors.InsufficientPrivilege, match=f"feature {fault} of class 'faults'"):
                ed.execute(
                    "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, %s, %s)",
                    (str(fault), region.region, solution, state_to_npz(forged)),
                )
            ed.rollback()
        ed.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'child')", (str(fault), region.region))
        ed.commit()  # choosing one side's rows stays hers, as resolve_conflict's parent or child does
    (stored,) = [r for r in tgsis.find_conflicts(conn, "e1")[0].regions if r.conflict]
    assert stored.solution == "child"


def test_a_cell_in_no_part_merges_by_region_and_stays_in_none(conn: Conn) -> None:
    # was: a triangle the parent added without a tgsis.part run (part -1 in the merge) made the parts'
    # rewrite refuse the merge ("part must hold part numbers 0 .. 2147483647")
    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    parts = (np.arange(len(surface.cells)) >= len(surface.cells) // 2).astype(np.int64)
    geoid = tgsis.insert_feature(
        conn, "faults", tgsis.Surface(surface.vertices, surface.cells, cell_properties={"part": parts})
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    runs = conn.execute("SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,))
    before = runs.fetchall()
    n = len(surface.cells)
    conn.execute(  # DEFAULT, as a psql user: one more triangle on the south edge, in no part
        "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 142, 143, 130)", (geoid, n)
    )
    conn.commit()
    move(conn, "e1", geoid, NORTH, (0.0, 0.0, 3.0))
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            runs = conn.execute(
                "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,)
            )
            assert runs.fetchall() == before, version
            cells = conn.execute("SELECT count(*) FROM tgsis.trgl WHERE geoid = %s", (geoid,)).fetchone()
            assert cells == (n + 1,)
        conn.commit()


def test_rows_without_property_rows_merge_by_region_and_stay_without(conn: Conn, fault: int) -> None:
    # was: a vertex and a triangle the parent added without property rows (NaN in the merge) made the
    # merge by region refuse the object (the integer facies "has no value"); a float one got a NaN row
    n = len(curved_surface().cells)
    with tgsis.in_version(conn, "DEFAULT"):  # as a psql user: rows of the model tables only
        conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 144, 3200.5, 2700.25, 1.0)", (fault,))
        conn.execute(
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 142, 143, 144)",
            (fault, n),
        )
    conn.commit()
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    expected = np.vstack([curved_surface().vertices, [[3200.5, 2700.25, 1.0]]])
    moved(expected, NORTH, (0.0, 0.0, 3.0))
    for version in ("DEFAULT", "e1"):
        ids, xyz, cells, porosity = stored_state(conn, version, fault)
        assert xyz.tobytes() == expected.tobytes() and len(cells) == n + 1
        assert 144 not in porosity and len(porosity) == 144, version
        fc = class_of_feature(conn, fault)
        with tgsis.in_version(conn, version):
            facies = conn.execute(
                sql.SQL("SELECT _idx FROM {} WHERE _geoid = %s").format(fc.qualified(fc.property_table("CELL") or "")),
                (fault,),
            ).fetchall()
        conn.commit()
        assert len(facies) == n and (n,) not in facies, version


def test_a_role_that_may_not_read_the_class_does_not_read_its_regions(conn: Conn, fault: int, db_dsn: str) -> None:
    # was: tgsis.conflict_regions was granted to every reader without the per-class rights of the model
    # tables: a role kept from the class's vertices read their ids, box and a recorded mesh's coordinates
    region = _overlapping_edits(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, region.region, "average")
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        query = "SELECT count(*) FROM tgsis.conflict_regions WHERE objectkey = %s"
        assert rita.execute(query, (str(fault),)).fetchone() == (1,)  # she may read it
        rita.rollback()
        conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader")
        conn.commit()
        assert rita.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault,)).fetchone() == (0,)
        assert rita.execute(query, (str(fault),)).fetchone() == (0,)
        rita.rollback()
    assert conn.execute(query, (str(fault),)).fetchone() == (1,)  # (the owner's reads are not filtered)


@pytest.mark.parametrize("setting", ["search_path = ''", "extra_float_digits = -15", "DateStyle = 'SQL, DMY'"])
def test_the_merge_by_region_under_other_session_settings(conn: Conn, fault: int, setting: str) -> None:
    # was: with a search_path without the cube extension's schema the write of the geometry row's box
    # failed (function cube(double precision[], double precision[]) does not exist)
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.execute("SET " + setting)
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    conn.execute("RESET ALL")
    conn.commit()
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, (0.125, -3.3, 7.77))
    moved(expected, SOUTH, (-1.1, 0.0, -2.9))
    assert stored_state(conn, "DEFAULT", fault)[1].tobytes() == expected.tobytes()
    with tgsis.in_version(conn, "DEFAULT"):
        box = conn.execute(
            "SELECT cube_ll_coord(bbox, 3), cube_ur_coord(bbox, 3) FROM tgsis.geometry WHERE geoid = %s", (fault,)
        ).fetchone()
    assert box == (expected[:, 2].min(), expected[:, 2].max())
