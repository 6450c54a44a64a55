"""TG308 found before the merge: a period whose merged geometry instants would have other topologies (issue 39).

A model-3 merge (slice by slice) whose slices that no solution changes — taken
from one side, or merged by themselves — already give one topology period
two topologies (a geometry instant added on one side, the period's triangles
changed on the other) can never merge: ``tgsis.merge_version`` refuses it
with ``PeriodTopologyError`` (TG308). ``tgsis.find_conflicts`` (and ``tgsis
version conflicts``, and the browser view) say so already: an object-level
conflict, no regions, the period named. A period whose topology depends on
the solutions still to be chosen is not refused there: the regions are listed.
"""

from __future__ import annotations

import json
from typing import Any

import psycopg
import pytest

import tgsis
from tests.test_merge_instants import SOUTH, make_evolving, move3
from tests.view_helpers import get, running_view
from tgsis.view.meshes import unpack

Conn = psycopg.Connection[Any]


def _instant_added_and_topology_changed(conn: Conn) -> int:
    """e1 adds geometry instant 2.5 (the period's old topology); DEFAULT removes triangle 0 from the period."""
    geoid = make_evolving(conn)
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND trglid = 0", (geoid,))
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("INSERT INTO tgsis.timet VALUES (%s, 1.0, 2.5)", (geoid,))
        conn.execute(
            "INSERT INTO tgsis.d4dvrtx SELECT geoid, timem, 2.5, nodeid, x, y, z FROM tgsis.d4dvrtx"
            " WHERE geoid = %s AND timet = 2.0",
            (geoid,),
        )
        conn.execute(
            "INSERT INTO evolving_cellpros SELECT _geoid, _timem, 2.5, _idx, porosity FROM evolving_cellpros"
            " WHERE _geoid = %s AND _timet = 2.0",
            (geoid,),
        )
    conn.commit()
    return geoid


def test_find_conflicts_reports_the_period_topology_refusal_before_the_merge(conn: Conn) -> None:
    geoid = _instant_added_and_topology_changed(conn)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    assert conflict.objectkey == str(geoid)
    assert conflict.regions == ()  # object level: nothing of it merges by region
    refusal = conflict.region_refusal or ""
    assert "topology period starting at 1.0" in refusal and "geometry instant 2.5" in refusal, refusal
    assert "TG308" in refusal and "resolve_conflict" in refusal, refusal
    stored = conn.execute("SELECT count(*) FROM tgsis.conflict_regions WHERE objectkey = %s", (str(geoid),)).fetchone()
    assert stored == (0,)
    # what the merge then says: the same refusal (nothing written)
    with pytest.raises(tgsis.PeriodTopologyError, match="period starting at 1.0"):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    # the way out it names
    tgsis.resolve_conflict(conn, "e1", "feature", str(geoid), "child")
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()


def test_the_command_line_reports_it(conn: Conn, db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    from tgsis.cli import main

    _instant_added_and_topology_changed(conn)
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--json"]) == 0
    [listed] = json.loads(capsys.readouterr().out)["conflicts"]
    assert listed["conflict_regions"] == []
    assert "TG308" in listed["region_refusal"] and "period starting at 1.0" in listed["region_refusal"]
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--regions"]) == 0
    text = capsys.readouterr().out
    assert "whole object:" in text and "period starting at 1.0" in text and "TG308" in text, text
    assert "merges slice by slice" not in text


def test_the_view_says_why_it_merges_as_a_whole(conn: Conn, db_dsn: str) -> None:
    geoid = _instant_added_and_topology_changed(conn)
    with running_view(db_dsn) as url:
        status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1")
    assert status == 200, body[:300]
    header, arrays = unpack(body)
    assert header["merges_by_region"] is False and header["regions"] == []
    assert "period starting at 1.0" in header["reason"] and "TG308" in header["reason"]
    assert header["n_vertices"] > 0


def test_a_topology_that_hangs_on_the_solutions_still_merges_by_region(conn: Conn) -> None:
    """The version removes a triangle; the parent moves its corner at one geometry instant: a region of that
    instant conflicts (its solution decides the topology there), the other instants merge the removal. Not
    refused at find time: a solution (child) merges it."""
    geoid = make_evolving(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND trglid = 0", (geoid,))
    conn.commit()
    move3(conn, "DEFAULT", geoid, 2.0, [0], (0.0, 0.0, 9.0))
    move3(conn, "DEFAULT", geoid, 2.0, SOUTH[:2], (0.0, 0.0, 1.0))
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    assert conflict.region_refusal is None and len(conflict.regions) > 0
    conflicting = [r.region for r in conflict.regions if r.conflict]
    assert conflicting and {r.times for r in conflict.regions if r.conflict} == {2.0}
    for region in conflicting:
        tgsis.resolve_region(conn, "e1", geoid, region, "child", discard_other=True)
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        left = conn.execute("SELECT count(*) FROM tgsis.d4dtrgl WHERE geoid = %s AND trglid = 0", (geoid,)).fetchone()
    assert left == (0,)


def test_the_export_says_it_merges_as_a_whole(conn: Conn, tmp_path: Any) -> None:
    """``--export``'s regions file agrees with find_conflicts: no merge by region, the TG308 reason named.

    (Was: ``"merges_by_region": true`` and ``"merges_by_itself": true`` for an object no solution can merge.)
    """
    geoid = _instant_added_and_topology_changed(conn)
    files = tgsis.export_conflict(conn, "e1", geoid, tmp_path, picture=False)
    [regions] = [f for f in files if f.name == f"{geoid}_regions.json"]
    document = json.loads(regions.read_text())
    assert document["merges_by_region"] is False and document["merges_by_itself"] is False, document
    assert "TG308" in document["reason"] and "period starting at 1.0" in document["reason"], document
    with pytest.raises(tgsis.PeriodTopologyError):  # what the merge says
        tgsis.merge_version(conn, "e1")
