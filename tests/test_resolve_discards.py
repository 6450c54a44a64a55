"""What a solution of a conflict throws away: the other side's edits since the common base, counted exactly.

Until merges are three-way, ``child`` takes the version's whole object (so the
parent's edits of it are lost) and ``parent`` the parent's (the version's are
lost). ``tgsis.conflict_discards`` counts them per table, the Python
``resolve_conflict`` returns them, and ``tgsis version resolve`` refuses a
solution that loses edits unless ``--discard-other`` is given.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg.conninfo import make_conninfo

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.roles import login_roles
from tests.storage_data import storage_of
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.db import versions as V

Conn = psycopg.Connection[Any]

SIDE = 5  # a 5 x 5 dome: 25 vertices, 32 triangles


def dome() -> tgsis.Surface:
    """A curved surface (z = 10 - r^2 / 2 over a 5 x 5 grid) with a porosity per vertex."""
    u, v = np.meshgrid(np.arange(SIDE, dtype=float), np.arange(SIDE, dtype=float))
    z = 10.0 - ((u - 2) ** 2 + (v - 2) ** 2) / 2
    vertices = np.stack([u.ravel(), v.ravel(), z.ravel()], axis=1)
    idx = np.arange(SIDE * SIDE).reshape(SIDE, SIDE)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return tgsis.Surface(vertices, triangles, name="dome", vertex_properties={"porosity": np.arange(SIDE * SIDE) / 100})


@pytest.fixture(autouse=True)
def private_state(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)


def make_story(conn: Conn) -> int:
    """The dome A and a flat B in DEFAULT, a child version 'edit'; both sides edit A, the version alone B.

    A, in the version: vertices 0, 1, 2 moved up (a part the parent leaves alone), vertex 12 (the top) up,
    vertex 6 to z = 7, the porosity of vertex 5, triangle 0 removed, vertex 25 and triangle 32 added.
    A, in DEFAULT: vertices 20, 21 moved down (another part), vertex 12 down, vertex 6 to z = 7 (the same
    edit as the version's), the porosities of vertices 5 and 7, triangle 31 removed, the feature's note.
    Returns A's geoid (B's is the next).
    """
    F.create_feature_class(
        conn, "domes", "SURFACE", feature_properties={"note": "text"}, cell_properties={"porosity": "float8"}
    )
    tgsis.enable_feature_versioning(conn)
    a = F.insert_feature(conn, "domes", dome())
    b = F.insert_feature(conn, "domes", dome())
    tgsis.create_version(conn, "edit")
    conn.commit()
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid IN (0, 1, 2)", (a,))
        conn.execute("UPDATE tgsis.vrtx SET z = z + 0.5 WHERE geoid = %s AND vrtxid = 12", (a,))
        conn.execute("UPDATE tgsis.vrtx SET z = 7 WHERE geoid = %s AND vrtxid = 6", (a,))
        conn.execute("UPDATE domes_cellpros SET porosity = 0.9 WHERE _geoid = %s AND _idx = 5", (a,))
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 0", (a,))
        conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 25, 5, 5, 3)", (a,))
        conn.execute("INSERT INTO domes_cellpros (_geoid, _idx, porosity) VALUES (%s, 25, 0.5)", (a,))
        conn.execute(
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, 32, 24, 19, 25)", (a,)
        )
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (b,))
        conn.commit()
    conn.execute("UPDATE tgsis.vrtx SET z = z - 1 WHERE geoid = %s AND vrtxid IN (20, 21)", (a,))
    conn.execute("UPDATE tgsis.vrtx SET z = z - 0.5 WHERE geoid = %s AND vrtxid = 12", (a,))
    conn.execute("UPDATE tgsis.vrtx SET z = 7 WHERE geoid = %s AND vrtxid = 6", (a,))
    conn.execute("UPDATE domes_cellpros SET porosity = porosity + 0.25 WHERE _geoid = %s AND _idx IN (5, 7)", (a,))
    conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 31", (a,))
    conn.execute("UPDATE domes SET note = 'checked' WHERE _geoid = %s", (a,))
    conn.commit()
    assert b == a + 1, (a, b)
    return a


BUILT_ONCE = {"story": make_story}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def story(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> dict[str, int]:
    """``make_story``'s domes A and B, already in the test's database (cloned, not built again)."""
    a = cloned_or_built(request, conn, built_once, "story", make_story)
    return {"A": a, "B": a + 1}


# (table, rows added, removed, changed, values changed), per solution: what it loses of the other side
LOST_BY_CHILD = [  # the parent's edits
    ("public.domes", 0, 0, 1, 1),  # the note
    ("vrtx", 0, 0, 3, 3),  # 20, 21 and the top moved (6: the same edit, kept)
    ("trgl", 0, 1, 0, 3),  # 31 comes back (3 vertex ids)
    ("public.domes_cellpros", 0, 0, 2, 2),  # porosity of 5 and 7
]
LOST_BY_PARENT = [  # the version's edits
    ("vrtx", 1, 0, 4, 4 + 3),  # 0, 1, 2 and the top moved; 25 added (x, y, z)
    ("trgl", 1, 1, 0, 3 + 3),  # 32 added, 0 comes back
    ("public.domes_cellpros", 1, 0, 1, 2),  # porosity of 5 changed, of 25 added
]


def _object_level(conn: Conn, a: int) -> None:
    """The version gives A's note another value too: A then merges as a whole object only (attributes changed on
    both sides), so whole-side solutions are what merges it. Without this, SQL finds A's regions and refuses
    ``child``, which would drop the parent's edit of vertices 20, 21 in a region that is no conflict."""
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE domes SET note = 'mine' WHERE _geoid = %s", (a,))
    conn.commit()


def _counts(conn: Conn, solution: str, key: int | None = None) -> list[tuple[Any, ...]]:
    rows = conn.execute(
        "SELECT shortname, rows_added, rows_removed, rows_changed, values_changed, objectkey, discarded"
        "  FROM tgsis.conflict_discards('edit', 'feature', %s) WHERE solution = %s",
        (None if key is None else str(key), solution),
    ).fetchall()
    return sorted(rows)


def test_each_solution_counts_the_other_sides_edits_against_the_base(conn: Conn, story: dict[str, int]) -> None:
    a = str(story["A"])
    assert [c.objectkey for c in tgsis.find_conflicts(conn, "edit")] == [a]  # B: only the version changed it
    assert _counts(conn, "child") == sorted((*r, a, "parent") for r in LOST_BY_CHILD)
    assert _counts(conn, "parent") == sorted((*r, a, "child") for r in LOST_BY_PARENT)
    assert _counts(conn, "child", story["B"]) == []
    # the Python API: the same, with the tables' descriptions from the registry
    discards = tgsis.conflict_discards(conn, "edit")
    vrtx = next(d for d in discards if d.solution == "parent" and d.shortname == "vrtx")
    assert (vrtx.discarded, vrtx.rows_added, vrtx.rows_changed, vrtx.values_changed) == ("child", 1, 4, 7)
    assert vrtx.description == "a vertex of a static geometry"


def test_the_counts_are_what_the_merge_then_loses(conn: Conn, story: dict[str, int]) -> None:
    a = story["A"]
    _object_level(conn, a)
    parent_before = _vertices(conn, "DEFAULT", a)
    child = _vertices(conn, "edit", a)
    conflict = tgsis.resolve_conflict(conn, "edit", "feature", a, "child")
    assert conflict.discarded is not None
    assert sorted(
        (d.shortname, d.rows_added, d.rows_removed, d.rows_changed, d.values_changed) for d in conflict.discarded
    ) == sorted(LOST_BY_CHILD)
    tgsis.merge_version(conn, "edit")
    after = _vertices(conn, "DEFAULT", a)
    assert after == child
    # of the vertices the parent moved (6, 12, 20, 21), the three the count said are lost now hold the version's z
    assert {k for k in (6, 12, 20, 21) if after[k] != parent_before[k]} == {12, 20, 21}


def _vertices(conn: Conn, version: str, geoid: int) -> dict[int, float]:
    with tgsis.in_version(conn, version):
        rows = conn.execute("SELECT vrtxid, z FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchall()
    return {int(k): float(z) for k, z in rows}


def test_parent_solution_and_a_manual_merge_that_holds_everything(conn: Conn, story: dict[str, int]) -> None:
    a = story["A"]
    conflict = tgsis.resolve_conflict(conn, "edit", "feature", a, "parent")
    assert conflict.discarded is not None
    assert sorted(
        (d.shortname, d.rows_added, d.rows_removed, d.rows_changed, d.values_changed) for d in conflict.discarded
    ) == sorted(LOST_BY_PARENT)
    assert all(d.discarded == "child" for d in conflict.discarded)
    assert tgsis.resolve_conflict(conn, "edit", "feature", a, "unsolved").discarded == ()
    # the version takes the parent's edits over: choosing child then loses nothing of the parent's
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z - 1 WHERE geoid = %s AND vrtxid IN (20, 21)", (a,))
        conn.execute("UPDATE tgsis.vrtx SET z = z - 1 WHERE geoid = %s AND vrtxid = 12", (a,))  # +0.5 - 1: the parent's
        conn.execute("UPDATE domes_cellpros SET porosity = 0.30 WHERE _geoid = %s AND _idx = 5", (a,))
        conn.execute("UPDATE domes_cellpros SET porosity = porosity + 0.25 WHERE _geoid = %s AND _idx = 7", (a,))
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 31", (a,))
        conn.execute("UPDATE domes SET note = 'checked' WHERE _geoid = %s", (a,))
        conn.commit()
    assert _counts(conn, "child") == []
    assert tgsis.resolve_conflict(conn, "edit", "feature", a, "manual").discarded == ()


def _run(dsn: str, capsys: pytest.CaptureFixture[str], *argv: str, code: int = 0) -> tuple[str, str]:
    assert main(["--dsn", dsn, *argv]) == code, capsys.readouterr()
    captured = capsys.readouterr()
    return captured.out, captured.err


def test_cli_resolve_refuses_to_discard_without_the_flag(
    db_dsn: str, conn: Conn, story: dict[str, int], capsys: pytest.CaptureFixture[str]
) -> None:
    a = str(story["A"])
    _object_level(conn, int(a))
    # stored, unsolved; object-level only (A does not merge by region: with regions, a side that drops the
    # other's edits outside the conflicting regions is refused whatever the flag, tests/test_resolve_region.py)
    V.find_conflicts(conn, "edit")
    conn.commit()
    before = conn.execute("SELECT * FROM tgsis.conflicts").fetchall()
    conn.rollback()
    out, err = _run(db_dsn, capsys, "version", "resolve", "edit", "feature", a, "child", code=1)
    assert out == ""
    assert "--discard-other" in err
    assert "vrtx: 3 changed" in err and "trgl: 1 removed" in err and "public.domes_cellpros: 2 changed" in err
    assert "the parent's edits" in err
    assert conn.execute("SELECT * FROM tgsis.conflicts").fetchall() == before  # nothing recorded
    assert [r[0] for r in before] and before[0][8] == "unsolved"
    conn.rollback()
    out, err = _run(db_dsn, capsys, "version", "resolve", "edit", "feature", a, "parent", code=1)
    assert "--discard-other" in err and "vrtx: 1 added, 4 changed (7 values)" in err and "the version's edits" in err
    # with the flag: recorded, and what it discarded is said
    out, _ = _run(db_dsn, capsys, "version", "resolve", "edit", "feature", a, "child", "--discard-other")
    assert out.startswith(f"feature {a} in edit: child\n")
    assert "discarded the parent's edits" in out and "vrtx: 3 changed (3 values)" in out
    assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == [("child",)]
    conn.rollback()
    # conflicts lists what each solution would discard; merge says what its solutions discarded
    out, _ = _run(db_dsn, capsys, "version", "conflicts", "edit")
    assert "child discards" in out and "parent discards" in out
    json_out, _ = _run(db_dsn, capsys, "version", "conflicts", "edit", "--json")
    assert '"discards"' in json_out
    out, _ = _run(db_dsn, capsys, "version", "merge", "edit")
    assert f"feature {a} (child): discarded the parent's edits" in out and "vrtx: 3 changed" in out


def test_cli_manual_and_a_solution_that_loses_nothing_need_no_flag(
    db_dsn: str, conn: Conn, story: dict[str, int], capsys: pytest.CaptureFixture[str]
) -> None:
    b = story["B"]
    conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (b,))  # the version's edit of B, alike
    conn.commit()
    out, _ = _run(db_dsn, capsys, "version", "resolve", "edit", "feature", str(b), "parent")
    assert out == f"feature {b} in edit: parent\n"
    out, _ = _run(db_dsn, capsys, "version", "resolve", "edit", "feature", str(story["A"]), "manual")
    assert "manual" in out and "discarded the parent's edits" in out


def test_roles_with_fewer_rights(
    db_dsn: str, conn: Conn, story: dict[str, int], capsys: pytest.CaptureFixture[str]
) -> None:
    a = str(story["A"])
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader_dsn = make_conninfo(db_dsn, user=roles.name("reader"))
        editor_dsn = make_conninfo(db_dsn, user=roles.name("editor"))
        # a reader sees what each solution would discard, and may not record one (with or without the flag)
        reader = roles.connect("reader")
        assert _counts(reader, "child") == sorted((*r, a, "parent") for r in LOST_BY_CHILD)
        reader.rollback()
        out, _ = _run(reader_dsn, capsys, "version", "conflicts", "edit", "--no-header")
        assert out.split("\t")[6] == (
            "vrtx: 3 changed (3 values); trgl: 1 removed (3 values); "
            "public.domes: 1 changed (1 value); public.domes_cellpros: 2 changed (2 values)"
        )
        # without the right to read some of the object's rows: the conflicts, and no counts (never made up)
        conn.execute(f"REVOKE SELECT ON {storage_of(conn, 'domes_cellpros', 'public')} FROM tgsis_reader")
        conn.commit()
        out, err = _run(reader_dsn, capsys, "version", "conflicts", "edit", "--no-header")
        assert out.rstrip("\n").split("\t")[:3] == ["feature", a, "unsolved"] and out.rstrip("\n").endswith("\t?\t?")
        assert "what each solution discards is not shown: permission denied" in err
        _, err = _run(
            reader_dsn, capsys, "version", "resolve", "edit", "feature", a, "child", "--discard-other", code=1
        )
        assert "may not resolve conflicts of version 'edit'" in err
        # an editor granted write on the version is refused without the flag, then resolves with it
        tgsis.grant_version(conn, "edit", "write", roles.name("editor"))
        conn.commit()
        # (the editor, a reader too, may not read the property rows: without the flag nothing can be checked)
        _, err = _run(editor_dsn, capsys, "version", "resolve", "edit", "feature", a, "parent", code=1)
        assert "cannot tell what solving feature" in err and "permission denied" in err and "--discard-other" in err
        assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == []
        conn.rollback()
        out, _ = _run(editor_dsn, capsys, "version", "resolve", "edit", "feature", a, "parent", "--discard-other")
        assert (
            out == f"feature {a} in edit: parent\n  what it discarded of the other side's edits is not shown: "
            "this role may not read the object's rows\n"
        )
        conn.execute(f"GRANT SELECT ON {storage_of(conn, 'domes_cellpros', 'public')} TO tgsis_reader")
        conn.commit()
        _run(editor_dsn, capsys, "version", "resolve", "edit", "feature", a, "unsolved")
        _, err = _run(editor_dsn, capsys, "version", "resolve", "edit", "feature", a, "parent", code=1)
        assert "--discard-other" in err and "vrtx: 1 added, 4 changed (7 values)" in err
        out, _ = _run(editor_dsn, capsys, "version", "resolve", "edit", "feature", a, "parent", "--discard-other")
        assert "discarded the version's edits" in out
        assert conn.execute("SELECT solution, solved_by FROM tgsis.conflicts").fetchone() == (
            "parent",
            roles.name("editor"),
        )
        # a merger that may not read the property rows merges all the same, and is told the counts are not shown
        tgsis.grant_version(conn, "DEFAULT", "merge", roles.name("editor"))
        conn.execute(f"REVOKE SELECT ON {storage_of(conn, 'domes_cellpros', 'public')} FROM tgsis_reader")
        conn.commit()
        out, _ = _run(editor_dsn, capsys, "version", "merge", "edit")
        assert out.startswith("merged edit into its parent: ") and "is not shown" in out
        assert _vertices(conn, "DEFAULT", int(a)) == _vertices(conn, "edit", int(a))


def test_sql_resolve_and_merge_say_what_they_discard(conn: Conn, story: dict[str, int]) -> None:
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(d.message_primary or ""))
    a = story["A"]
    _object_level(conn, a)
    conn.execute("SELECT tgsis.resolve_conflict('edit', 'feature', %s, 'child')", (str(a),))
    assert notices == [
        f"feature {a} of version 'edit' (solution child) recorded: the parent's edits discarded: "
        "public.domes: 1 changed (1 value); public.domes_cellpros: 2 changed (2 values); "
        "trgl: 1 removed (3 values); vrtx: 3 changed (3 values)"
    ]
    notices.clear()
    conn.execute("SELECT tgsis.resolve_conflict('edit', 'feature', %s, 'unsolved')", (str(a),))
    assert notices == []
    conn.execute("SELECT tgsis.resolve_conflict('edit', 'feature', %s, 'parent')", (str(a),))
    conn.commit()
    notices.clear()
    conn.execute("SELECT tgsis.merge_version('edit')")
    assert notices == [
        f"feature {a} of version 'edit' (solution parent) merged: the version's edits discarded: "
        "public.domes: 1 changed (1 value); public.domes_cellpros: 1 added, 1 changed (2 values); "
        "trgl: 1 added, 1 removed (6 values); vrtx: 1 added, 4 changed (7 values)"
    ]
    conn.commit()
    # merged: the version's edits of A are gone from both sides, B's are in the parent
    assert _vertices(conn, "DEFAULT", a) == _vertices(conn, "edit", a)


def test_refresh_says_what_its_solutions_discard_and_json(
    db_dsn: str, conn: Conn, story: dict[str, int], capsys: pytest.CaptureFixture[str]
) -> None:
    a = story["A"]
    doc, _ = _run(db_dsn, capsys, "version", "conflicts", "edit", "--json")
    [conflict] = json.loads(doc)["conflicts"]
    assert conflict["discards"]["parent"]["edits_of"] == "child"
    assert sorted(
        (t["table"], t["rows_added"], t["rows_removed"], t["rows_changed"], t["values_changed"])
        for t in conflict["discards"]["parent"]["tables"]
    ) == sorted(LOST_BY_PARENT)
    assert conflict["discards"]["child"]["tables"][0]["what"] == "a vertex of a static geometry"
    tgsis.resolve_conflict(conn, "edit", "feature", a, "parent")
    conn.commit()
    out, _ = _run(db_dsn, capsys, "version", "refresh", "edit")
    assert f"feature {a} (parent): discarded the version's edits: vrtx: 1 added, 4 changed (7 values)" in out
    assert _vertices(conn, "edit", a) == _vertices(conn, "DEFAULT", a)  # what it said is what went
    out, _ = _run(db_dsn, capsys, "version", "conflicts", "edit")
    assert out == ""


def test_bad_arguments(conn: Conn, story: dict[str, int]) -> None:
    with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
        tgsis.conflict_discards(conn, "nope")
    conn.rollback()
    with pytest.raises(tgsis.InvalidInputError, match="DEFAULT has no parent"):
        tgsis.conflict_discards(conn, "DEFAULT")
    conn.rollback()
    with pytest.raises(tgsis.NotFoundError, match="object class 'features' does not exist"):
        tgsis.conflict_discards(conn, "edit", "features")
    conn.rollback()
    assert tgsis.conflict_discards(conn, "edit", "feature", story["B"]) == []  # no conflict: nothing
    with pytest.raises(tgsis.NotFoundError, match="not in conflict"):
        tgsis.resolve_conflict(conn, "edit", "feature", story["B"], "child", discard_other=False)
    conn.rollback()
    with pytest.raises(tgsis.VersioningError, match="would discard the version's edits: vrtx: 1 added"):
        tgsis.resolve_conflict(conn, "edit", "feature", story["A"], "parent", discard_other=False)
    conn.rollback()
    assert conn.execute("SELECT count(*) FROM tgsis.conflicts WHERE solution <> 'unsolved'").fetchone() == (0,)
