"""A conflicting check-in's child version starts from the checked-out state, so the merge path sees both edits.

The story of issue 15 (part 4): a modeller checks a fault out, a colleague
edits it meanwhile in the same working revision, the modeller checks in with
``on_conflict="child"``. The child must hold the checked-out state plus the
modeller's edit only, ``find_conflicts`` must report the fault, and the merge
must do what the recorded solution says: the colleague's edit is never lost
without a decision.
"""

from __future__ import annotations

import json
import threading
from dataclasses import replace
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.roles import login_roles
from tgsis.db import features as F
from tgsis.db import versions as V

Conn = psycopg.Connection[Any]

THEIRS, MINE = 5, 6  # vertex the colleague moves, vertex the modeller moves (in base order): neighbours, so
# that the edits meet in one region (disjoint edits merge by region, tests/test_merge_regions.py)


def _grid(side: int = 20) -> tgsis.Surface:
    rng = np.random.default_rng(3)
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), rng.random(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": rng.random(side * side)},
        name="fault",
    )


def make_faults(conn: Conn) -> int:
    """The versioned class ``faults`` (a vertex property, a feature property), empty."""
    F.create_feature_class(
        conn, "faults", "SURFACE", cell_properties={"porosity": "float8"}, feature_properties={"author": "text"}
    )
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    return 0


BUILT_ONCE = {"faults": make_faults}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def faults(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> F.FeatureClass:
    """``make_faults``'s class, already in the test's database (cloned, not built again)."""
    cloned_or_built(request, conn, built_once, "faults", make_faults)
    fc = F.get_feature_class(conn, "faults")
    conn.commit()
    return fc


def _heights(conn: Conn, fid: int, version: str = "DEFAULT") -> dict[tuple[float, float], float]:
    """z of every vertex by its (x, y), as ``version`` holds the feature."""
    with tgsis.in_version(conn, version, local=True):
        mesh = F.fetch_feature(conn, "faults", fid).mesh
    conn.commit()
    assert isinstance(mesh, tgsis.Surface)
    return {(float(x), float(y)): float(z) for x, y, z in mesh.vertices}


def _xy(base: tgsis.Surface, i: int) -> tuple[float, float]:
    return float(base.vertices[i, 0]), float(base.vertices[i, 1])


def _moved(mesh: tgsis.Mesh, base: tgsis.Surface, moves: dict[int, float]) -> tgsis.Surface:
    """``mesh`` (any vertex order) with the vertices at the (x, y) of base vertices ``moves`` set to new heights."""
    vertices = mesh.vertices.copy()
    for i, z in moves.items():
        at = np.flatnonzero((vertices[:, :2] == base.vertices[i, :2]).all(axis=1))
        assert len(at) == 1
        vertices[at, 2] = z
    return tgsis.Surface(vertices, mesh.cells, vertex_properties=mesh.vertex_properties, name=mesh.name)


def _state(conn: Conn) -> tuple[Any, ...]:
    """What a refused call must leave as it was: versions, revisions, DEFAULT's working set, conflicts."""
    row = conn.execute(
        "SELECT (SELECT array_agg(name ORDER BY name) FROM tgsis.versions), "
        "(SELECT count(*) FROM tgsis.revisions), "
        "(SELECT workingset FROM tgsis.versions WHERE name = 'DEFAULT'), "
        "(SELECT count(*) FROM tgsis.conflicts)"
    ).fetchone()
    conn.rollback()
    assert row is not None
    return tuple(row)


def _checked_out_then_changed(conn: Conn, base: tgsis.Surface) -> tuple[int, tgsis.Checkout]:
    """A fault checked out, then moved by a colleague in DEFAULT's working revision (save over, committed)."""
    fid = F.insert_feature(conn, "faults", base, {"author": "ann"})
    conn.commit()
    co = tgsis.checkout(conn, fid)
    tgsis.save_feature(conn, "faults", fid, _moved(base, base, {THEIRS: 50.0}))
    conn.commit()
    return fid, co


# --------------------------------------------------------------------------- the whole story, each solution


@pytest.mark.parametrize("solution", ["parent", "child", "manual"])
def test_conflicting_checkin_meets_the_other_edit_in_the_merge(
    conn: Conn, faults: F.FeatureClass, solution: str
) -> None:
    base = _grid()
    fid, co = _checked_out_then_changed(conn, base)
    result = tgsis.checkin(conn, co, _moved(co.mesh, base, {MINE: -50.0}), on_conflict="child", child_version="mine")
    conn.commit()
    assert result.conflict and result.version == "mine"

    # the child holds the checked-out state and my edit: the colleague's edit is not reverted there...
    child = _heights(conn, fid, "mine")
    assert child[_xy(base, THEIRS)] == base.vertices[THEIRS, 2] and child[_xy(base, MINE)] == -50.0
    # ...so the child's difference is my edit only, and the colleague's change is the parent's side
    # object-level (versions.find_conflicts): with the mesh's regions stored (tgsis.find_conflicts), a whole side
    # that drops the other's edits outside the conflicting regions is refused (tests/test_resolve_region.py)
    conflicts = V.find_conflicts(conn, "mine")
    conn.commit()
    assert [(c.objectclass, c.objectkey, c.solution) for c in conflicts] == [("feature", str(fid), "unsolved")]
    assert "vrtx" in conflicts[0].conflicttype
    rows = tgsis.conflict_rows(conn, "mine", "feature", fid)
    conn.commit()
    changed = {
        (side, float(row["x"]), float(row["y"]), float(row["z"]))
        for table, side, _, row in rows
        if table == "vrtx" and row is not None
    }
    assert changed == {
        ("child", *_xy(base, MINE), -50.0),
        ("child", *_xy(base, THEIRS), base.vertices[THEIRS, 2]),
        ("parent", *_xy(base, MINE), base.vertices[MINE, 2]),
        ("parent", *_xy(base, THEIRS), 50.0),
    }

    # the merge the command line advises is refused until someone decides
    with pytest.raises(tgsis.UnsolvedConflictsError, match=str(fid)):
        tgsis.merge_version(conn, "mine")
    conn.rollback()
    assert _heights(conn, fid)[_xy(base, THEIRS)] == 50.0

    if solution == "manual":  # the merged mesh, written into the child first
        with tgsis.in_version(conn, "mine", local=True):
            merged = _moved(F.fetch_feature(conn, "faults", fid).mesh, base, {THEIRS: 50.0})  # type: ignore[arg-type]
            tgsis.save_feature(conn, "faults", fid, merged)
        conn.commit()
    tgsis.resolve_conflict(conn, "mine", "feature", fid, solution)
    conn.commit()
    tgsis.merge_version(conn, "mine", remove=True)
    conn.commit()

    final = _heights(conn, fid)
    expected = {
        "parent": (50.0, base.vertices[MINE, 2]),
        "child": (base.vertices[THEIRS, 2], -50.0),
        "manual": (50.0, -50.0),
    }[solution]
    assert (final[_xy(base, THEIRS)], final[_xy(base, MINE)]) == expected
    untouched = {_xy(base, i): float(base.vertices[i, 2]) for i in range(base.n_vertices) if i not in (THEIRS, MINE)}
    assert {k: final[k] for k in untouched} == untouched
    assert F.fetch_feature(conn, faults, fid).properties == {"author": "ann"}
    assert [v.name for v in tgsis.list_versions(conn)] == ["DEFAULT"]


def test_a_deleted_feature_meets_the_edit_too(conn: Conn, faults: F.FeatureClass) -> None:
    """Deleted by the colleague: the child keeps the edited fault, and the merge decides whether it comes back."""
    base = _grid()
    fid = F.insert_feature(conn, faults, base)
    conn.commit()
    co = tgsis.checkout(conn, fid)
    F.delete_feature(conn, faults, fid)
    conn.commit()
    result = tgsis.checkin(conn, co, _moved(co.mesh, base, {3: 9.0}), on_conflict="child")
    conn.commit()
    assert _heights(conn, fid, result.version)[_xy(base, 3)] == 9.0
    assert [c.objectkey for c in tgsis.find_conflicts(conn, result.version)] == [str(fid)]
    tgsis.resolve_conflict(conn, result.version, "feature", fid, "child")
    tgsis.merge_version(conn, result.version, remove=True)
    conn.commit()
    assert _heights(conn, fid)[_xy(base, 3)] == 9.0


# --------------------------------------------------------------------------- what check-out freezes


def test_checkout_freezes_the_working_revision_and_reads_there(conn: Conn, faults: F.FeatureClass) -> None:
    base = _grid(8)
    fid = F.insert_feature(conn, faults, base)
    conn.commit()
    before = tgsis.working_revision(conn)
    sets = conn.execute("SELECT cardinality(workingset) FROM tgsis.versions WHERE name = 'DEFAULT'").fetchone()
    conn.commit()
    co = tgsis.checkout(conn, fid)
    conn.commit()
    assert co.token.base_revision == co.token.revision == before
    assert tgsis.working_revision(conn) > before  # a new working revision: the cost of a check-out
    frozen = conn.execute(
        "SELECT visibleset IS NOT NULL FROM tgsis.revisions WHERE revision = %s", (before,)
    ).fetchone()
    assert frozen == (True,)
    grown = conn.execute("SELECT cardinality(workingset) FROM tgsis.versions WHERE name = 'DEFAULT'").fetchone()
    assert sets is not None and grown == (sets[0] + 1,)
    # the session is back where it was, and the frozen revision shows exactly the checked-out mesh
    assert tgsis.working_version(conn) == "DEFAULT" and tgsis.viewing_revision(conn) is None
    tgsis.save_feature(conn, faults, fid, _moved(base, base, {0: 1.0}))
    conn.commit()
    with tgsis.at_revision(conn, before, "DEFAULT", local=True):
        assert F.fetch_feature(conn, faults, fid).mesh.same_as(co.base.mesh)  # type: ignore[union-attr]
    conn.rollback()
    # inside a caller's transaction too, and the caller's viewing state survives it
    with conn.transaction():
        tgsis.goto_revision(conn, "DEFAULT", before, local=True)
        looked = tgsis.checkout(conn, fid)
        assert tgsis.viewing_revision(conn) == before  # looking back: that revision is the base
        assert looked.token.base_revision == before and looked.base.mesh.same_as(co.base.mesh)
    assert tgsis.working_revision(conn) == before + 1  # nothing more was frozen


def test_a_snapshot_older_than_the_freeze_freezes_nothing(conn: Conn, faults: F.FeatureClass) -> None:
    """Inside a caller's REPEATABLE READ transaction nothing is frozen; a session default of it does not matter."""
    fid = F.insert_feature(conn, faults, _grid(6))
    conn.commit()
    state = _state(conn)
    with conn.transaction():
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        assert tgsis.checkout(conn, fid).token.base_revision is None
    assert _state(conn) == state
    conn.execute("SET default_transaction_isolation = 'repeatable read'")
    conn.commit()
    assert tgsis.checkout(conn, fid).token.base_revision == state[2][-1]


def test_versioning_off_freezes_nothing(conn: Conn) -> None:
    F.create_feature_class(conn, "faults", "SURFACE", cell_properties={"porosity": "float8"})
    fid = F.insert_feature(conn, "faults", _grid(6))
    conn.commit()
    state = _state(conn)
    co = tgsis.checkout(conn, fid)
    assert co.token.base_revision is None
    assert _state(conn) == state


def test_a_reader_checks_out_without_freezing_or_waiting(db_dsn: str, conn: Conn, faults: F.FeatureClass) -> None:
    """A role without the write right freezes nothing and takes no lock; a writer's check-out waits for open writers."""
    base = _grid(8)
    fid = F.insert_feature(conn, faults, base)
    other = F.insert_feature(conn, faults, _grid(4))
    conn.commit()
    with (
        login_roles(db_dsn, {"rita": "tgsis_reader", "eddie": "tgsis_editor"}) as roles,
        psycopg.connect(db_dsn) as writer,
    ):
        reader, editor = roles.connect("rita"), roles.connect("eddie")
        for c in (reader, editor):
            c.execute("SET lock_timeout = '300ms'")
            c.commit()
        writer.execute("UPDATE tgsis.vrtx SET z = 77 WHERE geoid IN (%s, %s) AND vrtxid = 0", (fid, other))  # open
        state = _state(conn)
        co = tgsis.checkout(reader, fid)
        assert co.token.base_revision is None and co.token.revision == state[2][-1]
        assert co.base.mesh.same_as(F.fetch_feature(conn, faults, fid).mesh)  # type: ignore[arg-type]
        conn.rollback()
        assert _state(conn) == state  # nothing frozen
        with pytest.raises(tgsis.Error, match="lock"):
            tgsis.checkout(editor, fid)  # the writer's check-out waits for the open write
        editor.rollback()
        assert _state(conn) == state
        # without a timeout it waits, and then reads what the writer committed: the frozen revision holds it
        editor.execute("SET lock_timeout = 0")
        editor.commit()
        done: list[tgsis.Checkout] = []
        waiting = threading.Thread(target=lambda: done.append(tgsis.checkout(editor, fid)))
        waiting.start()
        waiting.join(0.5)
        assert waiting.is_alive() and not done
        writer.commit()
        waiting.join(10)
        assert done and done[0].token.base_revision == state[2][-1]
        assert 77.0 in done[0].mesh.vertices[:, 2]
        result = tgsis.checkin(editor, done[0], _moved(done[0].mesh, base, {3: -1.0}), on_conflict="child")
        assert not result.conflict and result.version == "DEFAULT"


# --------------------------------------------------------------------------- kept check-outs and child versions


def test_a_kept_checkout_has_a_base_too(conn: Conn, faults: F.FeatureClass) -> None:
    base = _grid()
    fid = F.insert_feature(conn, faults, base)
    conn.commit()
    first = tgsis.checkin(conn, tgsis.checkout(conn, fid), _moved(base, base, {1: 1.0}), keep=True)
    conn.commit()
    kept = first.checkout
    assert kept is not None and kept.token.base_revision is not None
    tgsis.save_feature(conn, faults, fid, _moved(base, base, {1: 1.0, THEIRS: 50.0}))  # the colleague, again in place
    conn.commit()
    result = tgsis.checkin(conn, kept, _moved(kept.mesh, base, {MINE: -50.0}), on_conflict="child")
    conn.commit()
    child = _heights(conn, fid, result.version)
    assert (child[_xy(base, 1)], child[_xy(base, THEIRS)], child[_xy(base, MINE)]) == (
        1.0,
        base.vertices[THEIRS, 2],
        -50.0,
    )
    assert [c.objectkey for c in tgsis.find_conflicts(conn, result.version)] == [str(fid)]


def test_checkout_in_a_child_version(conn: Conn, faults: F.FeatureClass) -> None:
    """Checked out of version 'work' and changed there meanwhile: the check-in's child is a child of 'work'."""
    base = _grid()
    fid = F.insert_feature(conn, faults, base)
    tgsis.create_version(conn, "work")
    conn.commit()
    with tgsis.in_version(conn, "work", local=True):
        co = tgsis.checkout(conn, fid)
        tgsis.save_feature(conn, faults, fid, _moved(base, base, {THEIRS: 50.0}))
    conn.commit()
    result = tgsis.checkin(conn, co, _moved(co.mesh, base, {MINE: -50.0}), on_conflict="child")
    conn.commit()
    parent = conn.execute(
        "SELECT p.name, c.initrevision FROM tgsis.versions c JOIN tgsis.versions p "
        "ON p.versionid = c.parentid WHERE c.name = %s",
        (result.version,),
    ).fetchone()
    assert parent == ("work", co.token.base_revision)
    assert [c.objectkey for c in tgsis.find_conflicts(conn, result.version)] == [str(fid)]
    with tgsis.in_version(conn, result.version, local=True):
        tgsis.save_feature(conn, faults, fid, _moved(base, base, {THEIRS: 50.0, MINE: -50.0}))
    tgsis.resolve_conflict(conn, result.version, "feature", fid, "manual")
    tgsis.merge_version(conn, result.version, remove=True)
    conn.commit()
    work = _heights(conn, fid, "work")
    assert (work[_xy(base, THEIRS)], work[_xy(base, MINE)]) == (50.0, -50.0)
    assert _heights(conn, fid) == {_xy(base, i): float(base.vertices[i, 2]) for i in range(base.n_vertices)}


# --------------------------------------------------------------------------- tokens that cannot take the child path


def test_tokens_from_before_frozen_checkouts(conn: Conn, faults: F.FeatureClass) -> None:
    base = _grid()
    fid, co = _checked_out_then_changed(conn, base)
    data = json.loads(co.token.to_json())
    del data["base_revision"]
    old = tgsis.CheckoutToken.from_json(json.dumps(data))
    assert old.base_revision is None and old.revision == co.token.revision
    # its revision is frozen and holds the checked-out state: the child path works
    result = tgsis.checkin(
        conn, tgsis.Checkout(old, co.base), _moved(co.mesh, base, {MINE: -50.0}), on_conflict="child"
    )
    conn.commit()
    assert result.conflict
    # an old check-out recorded the working revision, in which the colleague then wrote in place: refused
    working = tgsis.working_revision(conn)
    conn.rollback()
    before = tgsis.Checkout(replace(old, revision=working), co.base)
    state = _state(conn)
    with pytest.raises(
        tgsis.CheckoutConflictError,
        match=f"revision {working} of version 'DEFAULT' does not hold feature {fid} as the check-out token describes",
    ):
        tgsis.checkin(conn, before, co.mesh, on_conflict="child")
    conn.rollback()
    assert _state(conn) == state


def test_forged_and_stale_tokens_are_refused_and_change_nothing(conn: Conn, faults: F.FeatureClass) -> None:
    base = _grid()
    fid = F.insert_feature(conn, faults, base)
    tgsis.create_version(conn, "other")
    conn.commit()
    earlier = tgsis.checkout(conn, fid).token.base_revision  # a frozen revision of DEFAULT
    tgsis.save_feature(conn, faults, fid, _moved(base, base, {1: 1.0}))
    conn.commit()
    fid_co = tgsis.checkout(conn, fid)
    tgsis.save_feature(conn, faults, fid, _moved(base, base, {1: 1.0, THEIRS: 50.0}))
    conn.commit()
    other_rev = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = 'other'").fetchone()
    assert other_rev is not None and earlier is not None
    mine = _moved(fid_co.mesh, base, {MINE: -50.0})
    cases = [
        ({"base_revision": other_rev[0]}, "belongs to version other"),
        ({"base_revision": 10**6}, "does not exist"),
        ({"base_revision": -1}, "does not exist"),
        ({"base_revision": earlier}, "does not hold"),  # frozen, but before the state checked out
        ({"fingerprint": "0" * 32}, "does not hold"),
    ]
    state = _state(conn)
    heights = _heights(conn, fid)
    for change, message in cases:
        forged = tgsis.Checkout(replace(fid_co.token, **change), fid_co.base)
        with pytest.raises(tgsis.CheckoutConflictError, match=message) as refused:
            tgsis.checkin(conn, forged, mine, on_conflict="child")
        assert "check out again" in (refused.value.hint or ""), change
        conn.rollback()
        assert _state(conn) == state and _heights(conn, fid) == heights, change
    for text in (
        '{"feature_id": "1"}',
        json.dumps({**json.loads(fid_co.token.to_json()), "base_revision": "7"}),
        json.dumps({**json.loads(fid_co.token.to_json()), "revision": True}),
    ):
        with pytest.raises(tgsis.FileFormatError):
            tgsis.CheckoutToken.from_json(text)
    # the genuine token still works after all that
    assert tgsis.checkin(conn, fid_co, mine, on_conflict="child").conflict
    conn.commit()


def test_a_base_compressed_away_or_rebased_is_refused_clearly(conn: Conn, faults: F.FeatureClass) -> None:
    base = _grid()
    fid, co = _checked_out_then_changed(conn, base)
    tgsis.compress_versions(conn)  # nothing needs the check-out's revision
    conn.commit()
    state = _state(conn)
    with pytest.raises(tgsis.CheckoutConflictError, match="does not exist .*compress") as refused:
        tgsis.checkin(conn, co, _moved(co.mesh, base, {MINE: -50.0}), on_conflict="child")
    assert str(fid) in str(refused.value) and refused.value.sqlstate == "TG304"
    conn.rollback()
    assert _state(conn) == state
    # a check-out of a version that a merge re-based since
    tgsis.create_version(conn, "work")
    conn.commit()
    with tgsis.in_version(conn, "work", local=True):
        co = tgsis.checkout(conn, fid)
        tgsis.save_feature(conn, faults, fid, _moved(co.mesh, base, {THEIRS: 7.0}))
    conn.commit()
    tgsis.merge_version(conn, "work")
    conn.commit()
    state = _state(conn)
    with pytest.raises(tgsis.CheckoutConflictError, match="re-based"):
        tgsis.checkin(conn, co, _moved(co.mesh, base, {MINE: -50.0}), on_conflict="child")
    conn.rollback()
    assert _state(conn) == state


# --------------------------------------------------------------------------- the SQL underneath


def _sql_error(conn: Conn, query: str, params: tuple[Any, ...] = ()) -> tgsis.Error:
    with pytest.raises(tgsis.Error) as raised:
        with tgsis.errors.reraise():
            conn.execute(query, params)
    conn.rollback()
    return raised.value


def _scalar(conn: Conn, query: str, params: tuple[Any, ...] = ()) -> Any:
    row = conn.execute(query, params).fetchone()
    assert row is not None
    return row[0]


def test_create_version_on_a_frozen_base(conn: Conn, faults: F.FeatureClass) -> None:
    frozen = _scalar(conn, "SELECT tgsis.checkout_revision()")
    working = _scalar(conn, "SELECT tgsis.get_working_revision()")
    assert working > frozen
    seen = _scalar(conn, "SELECT visibleset FROM tgsis.revisions WHERE revision = %s", (frozen,))
    child = _scalar(conn, "SELECT tgsis.create_version('b', 'DEFAULT', NULL, %s)", (frozen,))
    assert _scalar(conn, "SELECT tgsis.get_working_revision()") == working  # the parent gets no new revision
    assert conn.execute("SELECT initrevision, workingset FROM tgsis.versions WHERE name = 'b'").fetchone() == (
        frozen,
        [*seen, child],
    )
    # p_base = the working revision is the ordinary create_version
    child_c = _scalar(conn, "SELECT tgsis.create_version('c', 'DEFAULT', NULL, %s)", (working,))
    assert child_c == working + 3 and _scalar(conn, "SELECT tgsis.get_working_revision()") == working + 2
    tgsis.refresh_version(conn, "b")
    conn.commit()
    b_own = _scalar(conn, "SELECT min(revision) FROM tgsis.revisions WHERE versionid = tgsis.version_id('b')")
    state = _state(conn)
    cases = [
        ("SELECT tgsis.create_version('x', 'b', NULL, %s)", (frozen,), "belongs to version DEFAULT"),
        ("SELECT tgsis.create_version('x', 'b', NULL, %s)", (b_own,), "re-based"),
        ("SELECT tgsis.create_version('x', 'DEFAULT', NULL, %s)", (child,), "belongs to version b"),
        ("SELECT tgsis.create_version('x', 'DEFAULT', NULL, 999999)", (), "does not exist"),
        ("SELECT tgsis.create_version('x', 'nope', NULL, %s)", (frozen,), "nope"),
    ]
    for query, params, message in cases:
        error = _sql_error(conn, query, params)
        assert error.sqlstate == "TG200" and message in str(error), (query, str(error))
        assert _state(conn) == state
    assert "p_base => NULL" in (_sql_error(conn, cases[3][0]).hint or "")


def test_checkout_revision_of_sql(conn: Conn, faults: F.FeatureClass) -> None:
    first = _scalar(conn, "SELECT tgsis.checkout_revision()")
    conn.commit()
    working = _scalar(conn, "SELECT tgsis.get_working_revision()")
    assert working > first
    tgsis.goto_revision(conn, "DEFAULT", first)
    assert _scalar(conn, "SELECT tgsis.checkout_revision()") == first  # looking back: nothing is frozen
    conn.commit()
    tgsis.goto_version(conn, "DEFAULT")
    assert _scalar(conn, "SELECT tgsis.get_working_revision()") == working
    conn.execute("SET tgsis.revision = '999999'")
    assert _sql_error(conn, "SELECT tgsis.checkout_revision()").sqlstate == "TG200"
    conn.execute("RESET tgsis.revision")
    conn.execute("SET tgsis.version = 'gone'")
    assert _sql_error(conn, "SELECT tgsis.checkout_revision()").sqlstate == "TG200"
    conn.execute("RESET tgsis.version")
    conn.commit()
    with conn.transaction():
        conn.execute("SET TRANSACTION READ ONLY")
        assert _scalar(conn, "SELECT tgsis.checkout_revision()") is None
    assert _scalar(conn, "SELECT tgsis.checkout_revision()") == working
