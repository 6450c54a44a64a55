"""Object-level ``base`` and ``average`` of a conflict (issue 39 item 3): tgsis.resolve_conflict, SQL and command line.

``base`` writes the object as the version was based on it into the version
(only the rows that differ) and records ``manual``, after saying what it
discards of both sides; a mesh with regions that merge by themselves is
refused (it would drop those edits). ``average`` is computed in Python: the
two sides' whole meshes averaged (the same parts kept, each conflicting
region averaged and attached to them), written into the version and
recorded ``manual``; SQL refuses it with a hint naming the command.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, make_fault, move, stored_state
from tests.test_conflict_regions import MIDDLE, everything
from tests.test_merge_average import _moved, _subdivided
from tgsis.cli import main
from tgsis.db import regions as R
from tgsis.errors import InvalidInputError, RegionSolutionError, VersioningError
from tgsis.merge3 import MeshState, apply_solutions

Conn = psycopg.Connection[Any]


def _middle_only(conn: Conn) -> int:
    """The fault with only the middle patch moved, on both sides, to other places: one region, a conflict."""
    geoid = make_fault(conn)
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()
    return geoid


def _base_rows() -> tuple[Any, Any]:
    surface = curved_surface()
    return np.arange(surface.n_vertices), surface.vertices


def _sql(conn: Conn, query: str, params: tuple[Any, ...]) -> tuple[str | None, str, str | None]:
    try:
        conn.execute(query, params)
    except psycopg.Error as exc:
        conn.rollback()
        return exc.sqlstate, exc.diag.message_primary or "", exc.diag.message_hint
    conn.rollback()
    raise AssertionError("not refused")


# --------------------------------------------------------------------------- base


def test_base_writes_the_base_into_the_version_and_the_merge_takes_it(conn: Conn) -> None:
    geoid = _middle_only(conn)
    [conflict] = tgsis.find_conflicts(conn, "e1")  # the regions stored: one, a conflict
    conn.commit()
    assert [r.conflict for r in conflict.regions] == [True]
    with pytest.raises(
        VersioningError, match=r"with base would discard the parent's edits: vrtx: 4 changed.*version's"
    ):
        tgsis.resolve_conflict(conn, "e1", "feature", geoid, "base", discard_other=False)
    conn.rollback()
    ids, xyz, _, _ = stored_state(conn, "e1", geoid)
    assert (xyz[MIDDLE, 2] != _base_rows()[1][MIDDLE, 2]).all()  # refused: the version still holds its edit
    conn.rollback()
    solved = tgsis.resolve_conflict(conn, "e1", "feature", geoid, "base")
    conn.commit()
    assert solved.solution == "manual" and solved.discarded is not None
    lost = {(d.discarded, d.shortname): d for d in solved.discarded}
    assert {d.solution for d in solved.discarded} == {"base"}
    assert lost["parent", "vrtx"].rows_changed == len(MIDDLE) and lost["child", "vrtx"].rows_changed == len(MIDDLE)
    base_ids, base_xyz = _base_rows()
    ids, xyz, _, _ = stored_state(conn, "e1", geoid)
    conn.commit()
    assert ids.tobytes() == base_ids.tobytes() and xyz.tobytes() == base_xyz.tobytes()  # the version holds the base
    [after] = [c for c in tgsis.find_conflicts(conn, "e1") if c.objectkey == str(geoid)]
    conn.commit()
    assert after.solution == "manual"  # holds for the version's new state
    tgsis.merge_version(conn, "e1")
    conn.commit()
    ids, xyz, _, _ = stored_state(conn, "DEFAULT", geoid)
    assert xyz.tobytes() == base_xyz.tobytes()  # both edits gone, as base said


def test_base_in_psql_says_what_it_discards_of_each_side(conn: Conn) -> None:
    geoid = _middle_only(conn)
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(d.message_primary or ""))
    row = conn.execute("SELECT solution FROM tgsis.resolve_conflict('e1', 'feature', %s, 'base')", (str(geoid),))
    assert row.fetchone() == ("manual",)
    conn.commit()
    assert any("(solution base)" in n and "the version's edits discarded: vrtx: 4 changed" in n for n in notices)
    assert any("(solution manual)" in n and "the parent's edits discarded: vrtx: 4 changed" in n for n in notices)
    _, xyz, _, _ = stored_state(conn, "e1", geoid)
    assert xyz.tobytes() == _base_rows()[1].tobytes()


def test_base_of_a_mesh_with_regions_that_merge_by_themselves_is_refused(conn: Conn, three_regions_clone: int) -> None:
    geoid = three_regions_clone  # north end in e1, south in DEFAULT (merge by themselves), middle on both
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    before = everything(conn)
    state, message, hint = _sql(conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'base')", (str(geoid),))
    assert state == "TG307" and "would drop the edits in regions" in message
    assert "the version's edit" in message and "the parent's edit" in message
    assert hint is not None and "tgsis.resolve_region" in hint and "'base'" in hint
    with pytest.raises(RegionSolutionError, match="no conflict"):
        tgsis.resolve_conflict(conn, "e1", "feature", geoid, "base")
    conn.rollback()
    assert everything(conn) == before
    # what the hint says: base for the conflicting region only, the rest merges by itself
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    tgsis.resolve_all_regions(conn, "e1", geoid, "base")
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    _, xyz, _, _ = stored_state(conn, "DEFAULT", geoid)
    assert xyz[MIDDLE].tobytes() == _base_rows()[1][MIDDLE].tobytes()
    assert (xyz[:24, 0] != _base_rows()[1][:24, 0]).all()  # the version's north end kept


def test_base_from_psql_finds_the_regions_itself_before_it_drops_every_edit(
    conn: Conn, three_regions_clone: int
) -> None:
    # was: with no regions stored (no Python call, SQL told the client finds them), base was recorded and
    # dropped the two ends each side edited alone, which merge by themselves
    geoid = three_regions_clone
    conn.execute("SELECT pg_catalog.set_config('tgsis.region_detection', 'client', false)")
    conn.execute("SELECT * FROM tgsis.find_conflicts('e1')")
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
    conn.rollback()
    state, message, _ = _sql(conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'base')", (str(geoid),))
    assert state == "TG307" and "would drop the edits in regions" in message


def test_base_needs_the_right_to_change_the_object(conn: Conn, db_dsn: str) -> None:
    from tests.roles import login_roles

    geoid = _middle_only(conn)
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as roles:
        conn.execute("SELECT tgsis.grant_version('e1', 'write', %s)", (roles.name("rita"),))
        conn.commit()
        before = everything(conn)
        rita = roles.connect("rita")
        state, _, _ = _sql(rita, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'base')", (str(geoid),))
        assert state == "42501"
        assert everything(conn) == before


# --------------------------------------------------------------------------- average


def test_average_of_a_whole_object_is_written_into_the_version(conn: Conn, fault_clone: int) -> None:
    geoid = fault_clone
    base = MeshState.from_mesh(curved_surface())
    from tests.test_merge_average import _write

    _write(conn, "e1", geoid, base, _subdivided(base))  # the version re-meshes a block, DEFAULT lifts it
    _write(conn, "DEFAULT", geoid, base, _moved(base))
    with pytest.raises(RegionSolutionError, match="discards"):
        tgsis.resolve_conflict(conn, "e1", "feature", geoid, "average", discard_other=False)
    conn.rollback()
    merge = tgsis.object_merge(conn, "e1", geoid)
    solved = tgsis.resolve_conflict(conn, "e1", "feature", geoid, "average")
    conn.commit()
    assert solved.solution == "manual"
    assert {d.side for d in solved.region_discards} == {"parent", "child"}
    assert {d.solution for d in solved.region_discards} == {"average"}
    [region] = merge.conflicts
    expected = apply_solutions(merge, {region.index: R.average_region(merge, region)}).state
    ids, xyz, cells, _ = stored_state(conn, "e1", geoid)
    conn.commit()
    assert ids.tobytes() == expected.vertex_ids.tobytes() and xyz.tobytes() == expected.vertices.tobytes()
    assert cells == {(int(i), *map(int, c)) for i, c in zip(expected.cell_ids, expected.cells, strict=True)}
    tgsis.merge_version(conn, "e1")
    conn.commit()
    ids, xyz, _, _ = stored_state(conn, "DEFAULT", geoid)
    assert xyz.tobytes() == expected.vertices.tobytes()


def test_average_of_an_object_with_regions_that_merge_by_themselves_points_to_region_all(
    conn: Conn, three_regions_clone: int
) -> None:
    geoid = three_regions_clone
    before = everything(conn)
    with pytest.raises(RegionSolutionError, match=r"halve the edits of regions") as refused:
        tgsis.resolve_conflict(conn, "e1", "feature", geoid, "average")
    conn.rollback()
    assert refused.value.hint and f"tgsis version resolve e1 {geoid} average --region all" in refused.value.hint
    assert everything(conn) == before


def test_average_in_sql_is_refused_with_the_command(conn: Conn) -> None:
    geoid = _middle_only(conn)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    before = everything(conn)
    state, message, hint = _sql(conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'average')", (str(geoid),))
    assert state == "TG100" and "computed by the Python library" in message
    assert hint == f"tgsis version resolve e1 feature {geoid} average"
    state, message, _ = _sql(conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'theirs')", (str(geoid),))
    assert state == "TG100" and "not parent, child, base, average, manual or unsolved" in message
    with pytest.raises(InvalidInputError, match="row of a versioned table"):
        tgsis.resolve_conflict(conn, "e1", "public.rocks", "1", "average")
    conn.rollback()
    assert everything(conn) == before


def test_the_command_line_resolves_an_object_with_base_and_average(
    conn: Conn, db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    geoid = _middle_only(conn)
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "version", "resolve", "e1", "feature", str(geoid), "base"]) != 0
    err = capsys.readouterr().err
    assert "discard" in err and "--discard-other" in err
    assert main(["--dsn", db_dsn, "version", "resolve", "e1", "feature", str(geoid), "average"]) != 0
    assert "--discard-other" in capsys.readouterr().err
    code = main(["--dsn", db_dsn, "version", "resolve", "e1", "feature", str(geoid), "average", "--discard-other"])
    out = capsys.readouterr().out
    assert code == 0 and "average written into the version, recorded manual" in out
    assert "average discards the parent's edit of 4 vertices" in out
    # the average of +5 and -7: -1 on every moved vertex, to the bit
    _, xyz, _, _ = stored_state(conn, "e1", geoid)
    base = _base_rows()[1]
    assert xyz[MIDDLE, 2].tobytes() == (0.5 * (base[MIDDLE, 2] + 5.0) + 0.5 * (base[MIDDLE, 2] - 7.0)).tobytes()
    conn.commit()
    code = main(["--dsn", db_dsn, "version", "resolve", "e1", "feature", str(geoid), "base", "--discard-other"])
    out = capsys.readouterr().out
    assert code == 0 and "base written into the version, recorded manual" in out and "discarded" in out
    _, xyz, _, _ = stored_state(conn, "e1", geoid)
    assert xyz.tobytes() == base.tobytes()


def test_average_needs_the_right_to_change_the_object(conn: Conn, db_dsn: str) -> None:
    from tests.roles import login_roles

    geoid = _middle_only(conn)
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as roles:
        conn.execute("SELECT tgsis.grant_version('e1', 'write', %s)", (roles.name("rita"),))
        conn.commit()
        before = everything(conn)
        _, xyz_before, _, _ = stored_state(conn, "e1", geoid)
        conn.commit()
        rita = roles.connect("rita")
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.resolve_conflict(rita, "e1", "feature", geoid, "average")
        rita.rollback()
        assert everything(conn) == before
        _, xyz_after, _, _ = stored_state(conn, "e1", geoid)
        conn.commit()
        assert xyz_after.tobytes() == xyz_before.tobytes()
